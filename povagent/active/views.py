"""Rendered views in the run folder, content-addressed: ``views/<sha256>.png``.

What it is for: a view is rendered once per run. Its PNG is stored by the SHA-256 of its bytes
(what rows and requests name it by), and a small index file per camera
(``views/cameras/<key>``, holding the SHA-256) lets a resumed run, which replays a killed
episode as a whole, find every view it already rendered without rendering it again.

A run folder is untrusted once it exists (a resumed run, a copied one): whoever prepared it may
have planted links or odd files there. So every write goes through the confined writer every
writer of povagent uses (:mod:`povagent.files.confined_write`: no link below the run folder is
followed, a file is written aside and renamed over its name, so a killed run leaves whole files
or none), and every read through :func:`read_view_file` (no link followed, no wait on a pipe, a
regular file of bounded size only). A stored view is used only if its bytes hash to the SHA-256
its name and its index say; anything else (a link, a pipe, a device, a file too large, other
bytes) is rendered again and written over, so a bad file costs one render, once.

What it must not do: render (it is handed the renderer), or decide what is shown.
"""

from __future__ import annotations

import hashlib
import json
import os
import stat
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from povagent.active.pose import Pose
from povagent.errors import ReadTargetError, WriteTargetError
from povagent.files.confined_read import read_at
from povagent.files.confined_write import ConfinedFolder

#: The folder inside the run folder, and the camera index inside it.
VIEWS = "views"
CAMERAS = "cameras"
#: The largest view file read back (a rendered view is a PNG of a few hundred kilobytes), and
#: the largest index file (a SHA-256 in hex).
MAX_VIEW_BYTES = 64 * 1024 * 1024
MAX_INDEX_BYTES = 128
_SHA = frozenset("0123456789abcdef")


def camera_key(house: str, pose: Pose) -> str:
    """A stable key of (house, camera): the SHA-256 of their JSON."""
    blob = json.dumps({"house": house, **pose.record()}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()


def read_view_file(folder: ConfinedFolder, name: str, limit: int) -> bytes | None:
    """The bytes of ``name`` in ``folder``, or ``None`` unless it is a regular file of at most
    ``limit`` bytes, read through the folder's descriptor by the one confined reader
    (:func:`~povagent.files.confined_read.read_at`: no link followed, no wait on a pipe, never
    past the bound)."""
    try:
        return read_at(folder, name, limit, what="view")
    except (OSError, ReadTargetError):
        return None


def view_file(run_dir: Path, sha256: str) -> Path | None:
    """``RUN/views/<sha256>.png`` for a reader that opens it by its path (the report draws
    it), when it is a regular file of bounded size in a ``views`` folder that is no link;
    ``None`` otherwise (missing, a link, a pipe, a device). A check, not a descriptor: it cannot
    see a swap made after it (see :meth:`ConfinedFolder.check_plain_file`)."""
    name = f"{sha256}.png"
    try:
        with ConfinedFolder(run_dir, VIEWS, create=False) as views:
            if views.descriptor is not None:
                st = os.stat(name, dir_fd=views.descriptor, follow_symlinks=False)
            else:
                st = os.lstat(views.path / name)
    except (OSError, WriteTargetError):
        return None
    return views.path / name if stat.S_ISREG(st.st_mode) and st.st_size <= MAX_VIEW_BYTES else None


@dataclass(frozen=True)
class StoredView:
    """A view as stored: its SHA-256, its file, and the bytes checked against that hash."""

    sha256: str
    path: Path
    png: bytes


class ViewStore:
    """The views of one run folder: ``root/views`` (``root`` is the folder the user named)."""

    def __init__(self, root: Path) -> None:
        self.root = Path(root)
        self.folder = self.root / VIEWS
        self.rendered = 0
        self.reused = 0
        with self._open() as views, views.sub(CAMERAS):
            pass  # made now, or a planted link refused in one line before any episode runs

    def _open(self) -> ConfinedFolder:
        return ConfinedFolder(self.root, VIEWS)

    def path_of(self, sha256: str) -> Path:
        """Where the view with this SHA-256 is stored."""
        if len(sha256) != 64 or not set(sha256) <= _SHA:
            raise ValueError(f"not a SHA-256: {sha256[:80]!r}")
        return self.folder / f"{sha256}.png"

    def view(self, house: str, pose: Pose, render: Callable[[Pose], bytes]) -> StoredView:
        """The view of ``pose``: from the folder when stored intact, else rendered and stored."""
        key = camera_key(house, pose)
        with self._open() as views, views.sub(CAMERAS) as cameras:
            stored = _stored(views, cameras, key)
            if stored is not None:
                self.reused += 1
                return stored
            data = render(pose)
            sha = hashlib.sha256(data).hexdigest()
            # unique temporary names: two episodes may store the same view at once
            views.write_replace(f"{sha}.png", data, unique=True)
            cameras.write_replace(key, sha.encode("ascii"), unique=True)
        self.rendered += 1
        return StoredView(sha, self.path_of(sha), data)


def _stored(views: ConfinedFolder, cameras: ConfinedFolder, key: str) -> StoredView | None:
    """The view the index names for ``key``, if its file is there and hashes to that name."""
    index = read_view_file(cameras, key, MAX_INDEX_BYTES)
    sha = index.decode("ascii", "replace").strip() if index is not None else ""
    if len(sha) != 64 or not set(sha) <= _SHA:
        return None
    data = read_view_file(views, f"{sha}.png", MAX_VIEW_BYTES)
    if data is None or hashlib.sha256(data).hexdigest() != sha:
        return None
    return StoredView(sha, views.path / f"{sha}.png", data)
