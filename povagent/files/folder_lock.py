"""The run-folder lock: one process at a time appends to a run folder's ``results.jsonl``.

Two processes appending to one file would each run the keys the other is running and write
them twice. An advisory ``flock`` on ``<run_dir>/.lock`` prevents it; the kernel drops the lock
when the process dies, even by SIGKILL, so a killed run never leaves its folder locked.
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import Iterator

from povagent.errors import ConfigError, WriteTargetError
from povagent.files.confined_write import open_inside

#: The lock file's name inside a run folder.
LOCK = ".lock"


@contextlib.contextmanager
def folder_lock(run_dir: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``run_dir`` for the block; :class:`ConfigError` when another
    process holds it. Where ``fcntl`` does not exist (Windows) the folder is not locked."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    try:
        fh = open_inside(run_dir, LOCK, "a")  # a link planted as the lock file is refused, not created through
    except WriteTargetError:
        raise
    except OSError as exc:  # a read-only mount, no permission: the user's to fix, one line
        raise ConfigError(f"{run_dir}: cannot write the run folder ({exc.strerror or exc}); choose a folder you can write to") from None
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(
                f"{run_dir}: another povagent process is running a pipeline into this folder; "
                f"wait for it to finish (then run again to resume) or choose another output folder"
            ) from None
        yield
    finally:
        fh.close()  # closing releases the lock
