"""The export folder: what may be written into it, who writes it, and what it already holds.

``export.json`` records an export's options and plan, so the same command resumes and other
options are refused naming the one that differs. A folder is written into only when it is new,
empty, or an export of ours; one process at a time holds it (an advisory ``flock`` on
``.lock``, dropped by the kernel when the process dies), so two exports into one folder never
remove each other's temporary files. Every check runs before the first byte is written: a
refused export leaves the folder as it was.
"""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from povagent.results.output_check import check_output_text
from povagent.train.export_options import ExportError, ExportOptions
from povagent.train.shards import Shard, atomic_file

MANIFEST = "export.json"
#: The version of what an export writes: raised when the same options write other bytes (2: the
#: rationales state where the speaker stood and the anchor's box in more views; 3: images named
#: after their content), so a resume never mixes the two in one export.
MANIFEST_VERSION = 3
#: The lock file's name inside an export folder.
LOCK = ".lock"
#: Entries of an export folder that are ours without a manifest (the lock a refused run left).
_OURS = {LOCK}


#: Options ``export.json`` records only when they differ from these defaults.
UNRECORDED_DEFAULTS = {"task": "point"}


def recorded_options(options: ExportOptions) -> dict[str, Any]:
    """The options as ``export.json`` records them; the point task, the default, is left out (an
    export of it records what it always did, and resumes one made before tasks existed)."""
    recorded = {**asdict(options), "conditions": list(options.conditions)}
    for key, default in UNRECORDED_DEFAULTS.items():
        if recorded[key] == default:
            del recorded[key]
    return recorded


def manifest(options: ExportOptions, shards: Sequence[Shard], dataset_root: Path) -> dict[str, Any]:
    """What ``export.json`` holds: the version, the options and the shard plan."""
    return {
        "version": MANIFEST_VERSION,
        "tool": "povagent export-train",
        "dataset": str(dataset_root),
        "options": recorded_options(options),
        "shards": [{"name": s.name, "split": s.split, "examples": [e.id for e in s.examples]} for s in shards],
    }


def check_out_folder(out: Path) -> None:
    """Refuse an ``--out`` that names a file, or a folder holding something not ours."""
    if out.is_symlink() and not out.is_dir():
        raise ExportError(f"--out {out}: a symbolic link to no folder; choose a folder")
    if out.exists() and not out.is_dir():
        raise ExportError(f"--out {out}: is a file, not a folder; choose a new or empty folder")
    if not out.is_dir():
        return
    try:
        names = {p.name for p in out.iterdir()}
    except OSError as exc:
        raise ExportError(f"--out {out}: cannot be read ({exc.strerror or exc}); choose a folder you can write to") from None
    if MANIFEST not in names and names - _OURS:
        raise ExportError(f"{out} is not empty and holds no export of ours: choose an empty or new folder")


def check_resume(out: Path, wanted: dict[str, Any]) -> None:
    """Refuse to resume an export made by another version, with other options, or from a
    dataset that changed; an ``export.json`` of the wrong shape is named with its field."""
    path = out / MANIFEST
    try:
        old = json.loads(path.read_bytes()[: 64 * 1024 * 1024])
    except (OSError, ValueError) as exc:
        raise ExportError(f"{path}: unreadable ({exc}); remove the export folder or choose another --out") from None
    if not isinstance(old, dict):
        raise ExportError(f"{path}: not an object (a {type(old).__name__}); remove the export folder or choose another --out")
    if old.get("version") != MANIFEST_VERSION:
        raise ExportError(
            f"{out} holds an export written by another version of export-train (format {old.get('version')!r}, now {MANIFEST_VERSION}): "
            "its shards would differ from the ones written now; choose another --out"
        )
    old_options = old.get("options")
    if not isinstance(old_options, dict):
        raise ExportError(f"{path}: field 'options' is not an object (a {type(old_options).__name__}); remove the export folder or choose another --out")
    for key, value in {**UNRECORDED_DEFAULTS, **wanted["options"]}.items():
        made_with = old_options.get(key, UNRECORDED_DEFAULTS.get(key))
        if made_with != value:
            raise ExportError(
                f"{out} holds an export made with {key}={made_with!r}, not {value!r}: "
                "run with the same options to resume, or choose another --out"
            )
    if old.get("shards") != wanted["shards"]:
        raise ExportError(f"{out}: the dataset's houses changed since this export began; choose another --out")


@contextlib.contextmanager
def export_folder(out: Path, wanted: dict[str, Any]) -> Iterator[None]:
    """Hold ``out`` for one export: checked, created, locked, its ``export.json`` written.

    :class:`ExportError` (one line) for a file, an unwritable place, a folder of someone else's,
    another export's options, or another process exporting into it.
    """
    check_out_folder(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExportError(f"--out {out}: cannot create the folder ({exc.strerror or exc}); choose a folder you can write to") from None
    with _locked(out):
        check_out_folder(out)  # again, now that no other export can change it
        if (out / MANIFEST).exists():
            check_resume(out, wanted)
        text = json.dumps(wanted, indent=1)
        check_output_text("export", text, out / MANIFEST)
        with atomic_file(out / MANIFEST, "w", inside=out) as handle:
            handle.write(text + "\n")
        yield


@contextlib.contextmanager
def _locked(out: Path) -> Iterator[None]:
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: the folder is not locked
        yield
        return
    try:
        fd = os.open(out / LOCK, os.O_WRONLY | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o644)
    except OSError as exc:
        raise ExportError(f"--out {out}: cannot write the folder ({exc.strerror or exc}); choose a folder you can write to") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ExportError(
                f"{out}: another export-train is writing into this folder; wait for it to finish "
                "(then run again to resume) or choose another --out"
            ) from None
        yield
    finally:
        os.close(fd)  # closing releases the lock
