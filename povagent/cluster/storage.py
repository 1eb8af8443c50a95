"""Does every worker see a folder as this machine sees it? One probe for every cluster task kind.

The client writes a file holding a random token into the folder; each worker reads it back,
writes one of its own beside it (which the client then reads) and says which of the named
paths it can see. Generation uses the answer to choose between writing in place and sending the
files back; a sweep, whose cells must write their own journals, refuses a folder the workers
cannot share.
"""

from __future__ import annotations

import os
import secrets
import socket
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: The probe's file name starts with this (a dot file: a folder listing hides it).
PROBE_PREFIX = ".povagent-probe-"


@dataclass
class StorageProbe:
    """What the workers answered: who reads the client's file, who writes one the client reads."""

    workers: int
    hosts: int
    readers: list[str] = field(default_factory=list)
    writers: list[str] = field(default_factory=list)
    blind: list[str] = field(default_factory=list)
    read_only: list[str] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)

    @property
    def shared(self) -> bool:
        """Every worker reads and writes the folder as this machine sees it."""
        return self.workers > 0 and len(self.readers) == len(self.writers) == self.workers


def look_at_storage(probe: str, token: str, reads: Sequence[str]) -> dict[str, Any]:
    """Run on each worker: does it read the client's probe, write beside it, see ``reads``?"""
    path = Path(probe)
    try:
        sees = path.read_text(encoding="utf-8") == token
    except OSError:
        sees = False
    written: str | None = None
    try:
        mine = path.with_name(f"{path.name}.{socket.gethostname()}.{os.getpid()}")
        mine.write_text(token, encoding="utf-8")
        written = str(mine)
    except OSError:
        pass
    return {"host": socket.gethostname(), "sees": sees, "written": written, "missing": [r for r in reads if not Path(r).exists()]}


def probe_storage(client: Any, folder: Path, reads: Sequence[Path] = ()) -> StorageProbe:
    """Ask every worker of ``client`` about ``folder`` (created if missing) and ``reads``."""
    folder.mkdir(parents=True, exist_ok=True)
    token = secrets.token_hex(16)
    probe = folder / f"{PROBE_PREFIX}{token[:8]}"
    probe.write_text(token, encoding="utf-8")
    try:
        answers = client.run(look_at_storage, str(probe), token, sorted({str(r) for r in reads}))
    finally:
        probe.unlink(missing_ok=True)
    result = StorageProbe(workers=len(answers), hosts=len({a["host"] for a in answers.values()}))
    for worker, answer in sorted(answers.items()):
        name = f"{worker} ({answer['host']})"
        written = answer["written"]
        if answer["sees"]:
            result.readers.append(name)
        else:
            result.blind.append(name)
        try:
            if written is not None and Path(written).read_text(encoding="utf-8") == token:
                result.writers.append(name)
            elif answer["sees"]:
                result.read_only.append(name)
        except OSError:  # written where this machine cannot see it
            if answer["sees"]:
                result.read_only.append(name)
        finally:
            if written is not None:
                Path(written).unlink(missing_ok=True)
        result.missing += [f"{name}: {m}" for m in answer["missing"]]
    return result
