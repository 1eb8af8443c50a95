"""What a checkpoint folder must be before ``transformers`` reads it.

A checkpoint folder is untrusted input: anyone may have made it (a download, a colleague's
training run, an unpacked archive). ``transformers`` opens its files by path and trusts what it
finds, so a named pipe where a file goes hangs it in ``open`` for good, a link to ``/dev/zero``
fills memory, ``config.json`` holding a list ends in an ``AttributeError`` traceback, a
safetensors header claiming 2^62 bytes ends in a ``SafetensorError``, and pickle weights
(``pytorch_model.bin``, read with ``torch.load``) are a format that can run code. This module
checks the folder first, reading files only through the confined reader
(:mod:`povagent.files.confined_read`), and says what is wrong in one line naming the file:

- every entry below the folder (links followed, as a Hugging Face cache snapshot links each
  file to a blob; hidden folders such as ``.git`` left out, ``transformers`` never reads them)
  is a regular file or a folder, and at most :data:`MAX_ENTRIES` of them;
- every file ``transformers`` reads whole (JSON, the chat template, vocabularies, code) holds at
  most :data:`MAX_TEXT_BYTES`;
- ``config.json`` is a JSON object, and so is every ``*.index.json``, whose ``weight_map``
  names files inside the folder;
- every ``*.safetensors`` file's header is a JSON object of at most :data:`MAX_HEADER_BYTES`
  inside the file, and every tensor's data lies inside the file;
- weights are safetensors: a folder holding only pickle weights is refused (convert them with
  ``safetensors``), and the model is loaded with ``use_safetensors=True``, so a pickle beside
  safetensors weights is never read.

It reads headers and small files only, never a tensor, and imports neither ``torch`` nor
``transformers``. Whether a checkpoint's own Python code may run is not decided here (see
:mod:`povagent.config.remote_code`).
"""

from __future__ import annotations

import json
import os
import struct
from pathlib import Path, PurePosixPath
from typing import Any

from povagent.errors import ConfigError
from povagent.files.confined_read import check_regular, open_regular, read_regular

#: A safetensors header larger than this is not one (the format caps it at 100 MB).
MAX_HEADER_BYTES = 100_000_000
#: Files read whole (configs, vocabularies, templates, code): the largest real tokenizer.json
#: files are tens of MiB.
MAX_TEXT_BYTES = 128 << 20
#: Entries below a checkpoint folder: a real one has tens.
MAX_ENTRIES = 10_000
#: Suffixes of files ``transformers`` reads whole.
TEXT_SUFFIXES = (".json", ".jinja", ".txt", ".model", ".py", ".tiktoken", ".vocab", ".merges")
#: Suffixes of pickle weights (``torch.load``).
PICKLE_SUFFIXES = (".bin", ".pt", ".pth", ".pkl", ".ckpt")


def _refuse(folder: Path, message: str) -> ConfigError:
    return ConfigError(f"checkpoint {folder}: {message}")


def read_json_object(path: Path, folder: Path, what: str) -> dict[str, Any]:
    """A JSON file of the checkpoint that must hold an object (a ``ConfigError`` otherwise)."""
    data = read_regular(path, MAX_TEXT_BYTES, what=what)
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise _refuse(folder, f"{path.name}: not JSON text ({str(exc)[:120]})") from None
    if not isinstance(doc, dict):
        raise _refuse(folder, f"{path.name}: holds a JSON {type(doc).__name__}, not an object (key: value)")
    return doc


def _entries(folder: Path) -> list[Path]:
    """Every file below ``folder`` (folders descended, links to folders checked, not descended),
    refusing any entry that is neither a regular file nor a folder, and too many entries."""
    files: list[Path] = []
    seen = 0
    for here, dirs, names in os.walk(folder):
        dirs[:] = [d for d in dirs if not d.startswith(".")]  # .git, .cache: never read by transformers
        for name in [*names, *dirs]:
            seen += 1
            if seen > MAX_ENTRIES:
                raise _refuse(folder, f"holds more than {MAX_ENTRIES} files and folders; is this a checkpoint folder?")
            path = Path(here) / name
            if path.is_dir():
                continue
            check_regular(path, MAX_TEXT_BYTES if path.suffix in TEXT_SUFFIXES else None, what="checkpoint file")
            files.append(path)
    return files


def _check_safetensors(path: Path, folder: Path) -> None:
    """The header of a safetensors file: bounded, inside the file, a JSON object whose tensors'
    data lies inside the file."""
    with open_regular(path, what="weights file") as fh:
        size = os.fstat(fh.fileno()).st_size
        first = fh.read(8)
        if len(first) < 8:
            raise _refuse(folder, f"{path.name}: {size} bytes, too short for a safetensors file")
        (length,) = struct.unpack("<Q", first)
        if length > min(MAX_HEADER_BYTES, size - 8):
            raise _refuse(
                folder,
                f"{path.name}: its safetensors header claims {length} bytes, more than the file holds ({size} bytes) "
                f"or the format allows ({MAX_HEADER_BYTES})",
            )
        raw = fh.read(length)
    try:
        header = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        raise _refuse(folder, f"{path.name}: its safetensors header is not JSON text") from None
    if not isinstance(header, dict):
        raise _refuse(folder, f"{path.name}: its safetensors header is not a JSON object")
    data_bytes = size - 8 - length
    for name, tensor in header.items():
        if name == "__metadata__":
            continue
        offsets = tensor.get("data_offsets") if isinstance(tensor, dict) else None
        if not (
            isinstance(offsets, list)
            and len(offsets) == 2
            and all(type(o) is int for o in offsets)
            and 0 <= offsets[0] <= offsets[1] <= data_bytes
        ):
            raise _refuse(folder, f"{path.name}: tensor {str(name)[:80]!r} claims data outside the file's {data_bytes} bytes")


def _check_index(path: Path, folder: Path) -> None:
    """A weights index: a JSON object whose ``weight_map`` names files inside the folder."""
    index = read_json_object(path, folder, "weights index")
    weight_map = index.get("weight_map", {})
    if not isinstance(weight_map, dict):
        raise _refuse(folder, f"{path.name}: weight_map is not a JSON object")
    for target in weight_map.values():
        where = PurePosixPath(target) if isinstance(target, str) else None
        if where is None or not where.parts or where.is_absolute() or ".." in where.parts:
            raise _refuse(folder, f"{path.name}: weight_map names {str(target)[:80]!r}, not a file inside the folder")


def check_checkpoint_folder(folder: Path) -> None:
    """Refuse, in one line naming the file, a checkpoint folder ``transformers`` must not read
    (see the module docstring); return quietly for one it may."""
    try:
        _check(folder)
    except FileNotFoundError as exc:  # a link leading nowhere
        raise _refuse(folder, f"{exc.filename}: a link leading nowhere") from None
    except OSError as exc:  # unreadable, a loop of links
        raise _refuse(folder, f"{exc.filename or 'a file'}: cannot be read ({exc.strerror or exc})") from None


def _check(folder: Path) -> None:
    files = _entries(folder)
    config = folder / "config.json"
    if config.exists():
        read_json_object(config, folder, "config")
    for path in sorted(p for p in files if p.parent == folder and p.name.endswith(".index.json")):
        _check_index(path, folder)
    weights = [p for p in files if p.parent == folder]
    safetensors = [p for p in weights if p.suffix == ".safetensors"]
    pickles = [p for p in weights if p.suffix in PICKLE_SUFFIXES]
    if pickles and not safetensors:
        raise _refuse(
            folder,
            f"its weights are pickle files ({', '.join(sorted(p.name for p in pickles)[:3])}), which can run code when "
            "loaded; povagent loads safetensors weights only: convert them (safetensors.torch.save_file) and load that folder",
        )
    for path in sorted(safetensors):
        _check_safetensors(path, folder)
