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
import os
import struct
from pathlib import Path

from povagent.files.confined_read import open_regular, read_regular
from povagent_plugins.backends.checkpoint_checks import MAX_HEADER_BYTES, MAX_TEXT_BYTES

#: Files that describe the model, hashed whole when present.
DESCRIBING_FILES = ("config.json", "generation_config.json")
#: Bytes read from the end of each weights file.
TAIL_BYTES = 1 << 20


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
    with open_regular(path, what="weights file") as fh:
        head = fh.read(8)
        if len(head) < 8:
            return head
        (size,) = struct.unpack("<Q", head)
        return head + fh.read(min(size, MAX_HEADER_BYTES))


def _tail(path: Path) -> bytes:
    with open_regular(path, what="weights file") as fh:
        fh.seek(max(0, os.fstat(fh.fileno()).st_size - TAIL_BYTES))
        return fh.read(TAIL_BYTES)


def checkpoint_fingerprint(folder: Path) -> str:
    """SHA-256 (hex) of what identifies the checkpoint in ``folder`` (see the module docstring).

    Every file is read through the confined reader, bounded (a pipe or a device there is a
    one-line error, never a wait): call :func:`~povagent_plugins.backends.checkpoint_checks.check_checkpoint_folder`
    first for the messages that say what a bad folder holds."""
    digest = hashlib.sha256()
    for name in DESCRIBING_FILES:
        path = folder / name
        if path.exists():
            digest.update(f"{name}\0".encode() + read_regular(path, MAX_TEXT_BYTES, what="checkpoint file"))
    for path in sorted(folder.glob("*.index.json")):
        digest.update(f"{path.name}\0".encode() + read_regular(path, MAX_TEXT_BYTES, what="weights index"))
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
