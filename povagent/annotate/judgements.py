"""Manual assessment's record: one journalled file of judgements per judge, beside the runs.

A judgement says whether a prediction is where the sentence places the object from the
speaker's view (``success``), is not (``failure``), or cannot be told (``cant_tell``), with an
optional note. Each is one line of ``<judgements folder>/<judge>.jsonl``, appended and fsynced
before the page hears "saved", so a judge session stopped at any moment resumes after the last
judgement it acknowledged. The report reads these files (:mod:`povagent.report.manual`); a line
that does not read as a judgement (a torn last line) is skipped, never guessed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from povagent.run.confined_read import MAX_DOCUMENT_BYTES, read_regular
from povagent.run.confined_write import ConfinedFolder

Verdict = Literal["success", "failure", "cant_tell"]
VERDICTS: tuple[str, ...] = ("success", "failure", "cant_tell")
#: The longest note kept.
MAX_NOTE_CHARS = 2000
#: The folder of judgement files a report looks for beside (or inside) its source folder.
JUDGEMENTS_FOLDER = "judgements"


class Judgement(BaseModel):
    """One judge's verdict on one prediction (a line of the judge's file)."""

    model_config = ConfigDict(frozen=True)

    #: the prediction judged: a digest of its run and row key (the page shows nothing else of it)
    item: str
    judge: str
    verdict: Verdict
    note: str = Field("", max_length=MAX_NOTE_CHARS)
    #: how long the judge looked before deciding
    seconds: float = Field(ge=0)
    #: the system that made the prediction (never shown to the judge)
    system: str
    run_name: str
    key: str
    instance_id: str
    condition: str


def read_judgements(path: Path) -> list[Judgement]:
    """The judgements in one judge's file, in order; lines that are not judgements are skipped."""
    if not path.exists():
        return []
    out: list[Judgement] = []
    for line in read_regular(path, MAX_DOCUMENT_BYTES, what="judgements file").splitlines():
        try:
            out.append(Judgement.model_validate(json.loads(line)))
        except (ValueError, RecursionError, ValidationError):
            continue
    return out


class JudgementJournal:
    """A judge's file, appended one fsynced line at a time (written inside its folder only)."""

    def __init__(self, folder: Path, judge: str) -> None:
        self.folder = folder
        self.path = folder / f"{judge}.jsonl"
        # a torn last line (a kill mid-write) is ended before the next line, so it stays alone
        self._torn = self.path.exists() and not read_regular(self.path, MAX_DOCUMENT_BYTES, what="judgements file").endswith(b"\n") \
            and self.path.stat().st_size > 0

    def read(self) -> list[Judgement]:
        """What the judge has judged so far."""
        return read_judgements(self.path)

    def append(self, judgement: Judgement) -> None:
        """Make ``judgement`` durable: written, flushed and fsynced before this returns."""
        with ConfinedFolder(self.folder) as folder, folder.open_append(self.path.name, binary=True) as f:
            f.write((("\n" if self._torn else "") + judgement.model_dump_json() + "\n").encode())
            f.flush()
            os.fsync(f.fileno())
        self._torn = False
