"""Which checkpoint the in-process backend runs: its folder and a fingerprint of its files.

The fingerprint goes into the backend's identity, so into every row's ``model`` and the
response-cache key: two checkpoints at one path (a model trained again into the same folder)
never share cached answers. It is a SHA-256 over the files that say what the model is, read
without loading a tensor: ``config.json``, ``generation_config.json``, the weights index
(``*.index.json``) and, for each weights file, its size, its safetensors header (tensor names,
dtypes, shapes, offsets) and its last MiB (training changes every tensor's values, so the tail
of the data differs even when the header does not). A Hub id is looked up in the local Hugging
Face cache only (never downloaded here); before its first download it has no fingerprint, and
its identity names the id and ``revision``.

This module reads files; it never imports ``torch`` or ``transformers``.
"""

from __future__ import annotations

import hashlib
import struct
from pathlib import Path

#: Files that describe the model, hashed whole when present.
DESCRIBING_FILES = ("config.json", "generation_config.json")
#: Bytes read from the end of each weights file.
TAIL_BYTES = 1 << 20
#: A safetensors header larger than this is not one (the format caps it at 100 MB).
MAX_HEADER_BYTES = 100_000_000


def checkpoint_folder(model: str, revision: str | None = None) -> Path | None:
    """The local folder holding ``model``: the path itself when it is a folder, else the Hub
    id's snapshot in the local Hugging Face cache, else ``None`` (not downloaded yet)."""
    path = Path(model).expanduser()
    if path.is_dir():
        return path.resolve()
    if model.count("/") != 1 or model.startswith((".", "/", "~")):
        return None
    try:
        from huggingface_hub import snapshot_download

        return Path(snapshot_download(model, revision=revision, local_files_only=True))
    except Exception:  # not in the cache (or not a valid id): nothing to fingerprint yet
        return None


def _safetensors_header(path: Path) -> bytes:
    with path.open("rb") as fh:
        head = fh.read(8)
        if len(head) < 8:
            return head
        (size,) = struct.unpack("<Q", head)
        return head + fh.read(min(size, MAX_HEADER_BYTES))


def _tail(path: Path) -> bytes:
    with path.open("rb") as fh:
        fh.seek(max(0, path.stat().st_size - TAIL_BYTES))
        return fh.read(TAIL_BYTES)


def checkpoint_fingerprint(folder: Path) -> str:
    """SHA-256 (hex) of what identifies the checkpoint in ``folder`` (see the module docstring)."""
    digest = hashlib.sha256()
    for name in DESCRIBING_FILES:
        path = folder / name
        if path.is_file():
            digest.update(f"{name}\0".encode() + path.read_bytes())
    for path in sorted(folder.glob("*.index.json")):
        digest.update(f"{path.name}\0".encode() + path.read_bytes())
    weights = sorted(p for p in folder.iterdir() if p.suffix in (".safetensors", ".bin") and p.is_file())
    for path in weights:
        digest.update(f"{path.name}\0{path.stat().st_size}\0".encode())
        if path.suffix == ".safetensors":
            digest.update(_safetensors_header(path))
        digest.update(_tail(path))
    return digest.hexdigest()


def checkpoint_label(model: str, fingerprint: str | None) -> str:
    """How rows name the model: the path or id, and the fingerprint's first 12 digits."""
    return f"{model}#{fingerprint[:12]}" if fingerprint else model
