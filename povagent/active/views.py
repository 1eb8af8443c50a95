"""Rendered views in the run folder, content-addressed: ``views/<sha256>.png``.

What it is for: a view is rendered once per run. Its PNG is stored by the SHA-256 of its bytes
(what rows and requests name it by), and a small index file per camera
(``views/cameras/<key>``, holding the SHA-256) lets a resumed run, which replays a killed
episode as a whole, find every view it already rendered without rendering it again. Both are
written atomically (a temporary file renamed into place), so a killed run leaves whole files
or none. What it must not do: render (it is handed the renderer), or decide what is shown.
"""

from __future__ import annotations

import hashlib
import json
import os
import uuid
from collections.abc import Callable
from pathlib import Path

from povagent.active.pose import Pose

#: The folder inside the run folder.
VIEWS = "views"
_SHA = frozenset("0123456789abcdef")


def camera_key(house: str, pose: Pose) -> str:
    """A stable key of (house, camera): the SHA-256 of their JSON."""
    blob = json.dumps({"house": house, **pose.record()}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()


def _write_atomically(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}")
    tmp.write_bytes(data)
    os.replace(tmp, path)


class ViewStore:
    """The views of one run folder (``folder`` is ``RUN/views``)."""

    def __init__(self, folder: Path) -> None:
        self.folder = Path(folder)
        self.rendered = 0
        self.reused = 0

    def path_of(self, sha256: str) -> Path:
        """Where the view with this SHA-256 is stored."""
        if len(sha256) != 64 or not set(sha256) <= _SHA:
            raise ValueError(f"not a SHA-256: {sha256[:80]!r}")
        return self.folder / f"{sha256}.png"

    def view(self, house: str, pose: Pose, render: Callable[[Pose], bytes]) -> tuple[str, Path]:
        """``(sha256, path)`` of the view of ``pose``: from the folder, or rendered and stored."""
        index = self.folder / "cameras" / camera_key(house, pose)
        try:
            sha = index.read_text(encoding="ascii").strip()
            path = self.path_of(sha)
            if path.is_file():
                self.reused += 1
                return sha, path
        except (OSError, ValueError, UnicodeDecodeError):
            pass
        data = render(pose)
        sha = hashlib.sha256(data).hexdigest()
        path = self.path_of(sha)
        index.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file():
            _write_atomically(path, data)
        _write_atomically(index, sha.encode("ascii"))
        self.rendered += 1
        return sha, path
