"""Manual assessment's record: one journalled file of judgements per judge, beside the runs.

A judgement names the prediction it judges by :func:`judged_item`: a digest of the judged run's
identity (its folder's ``config.yaml``, which holds the run's output folder and every setting),
the row's key and the prediction itself, never a run's or a cell's name: two sweeps whose cells
share names share no item, and a report keeps only the judgements of items its own runs hold.

A judgement says whether a prediction is where the sentence places the object from the
speaker's view (``success``), is not (``failure``), or cannot be told (``cant_tell``), with an
optional note. Each is one line of ``<judgements folder>/<judge>.jsonl``, appended and fsynced
before the page hears "saved", so a judge session stopped at any moment resumes after the last
judgement it acknowledged. The file is written and read through the confined writer and reader
(:mod:`povagent.files.confined_write`): the folder the judge named is followed, but the default
``judgements/`` beside the runs, and the file in it, are never followed as links (one planted
there is refused, nothing written). The report reads these files (:mod:`povagent.report.manual`);
a line that does not read as a judgement (a torn last line) is skipped, never guessed.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_inside, read_regular
from povagent.files.confined_write import ConfinedFolder
from povagent.results.finished_run import CONFIG_FILE, MAX_CONFIG_BYTES

Verdict = Literal["success", "failure", "cant_tell"]
VERDICTS: tuple[str, ...] = ("success", "failure", "cant_tell")
#: The longest note kept.
MAX_NOTE_CHARS = 2000
#: The folder of judgement files a report looks for beside (or inside) its source folder.
JUDGEMENTS_FOLDER = "judgements"


def run_identity(folder: Path) -> str:
    """The identity of the run in ``folder``: the digest of its ``config.yaml`` (the resolved
    pipeline, its output folder included), read with its bound. Not its name: cells of two
    sweeps may share names, never a config."""
    try:
        config = read_regular(folder / CONFIG_FILE, MAX_CONFIG_BYTES, what="run config")
    except FileNotFoundError:
        config = b""
    return hashlib.sha256(config).hexdigest()


def judged_item(identity: str, key: str, prediction: Any) -> str:
    """A prediction's name in the judgement files: a digest of its run's :func:`run_identity`,
    its row key and the prediction (frame, x, y), which tells the judge nothing. A run redone
    in place with another answer is another item."""
    point = f"{prediction.selected_image}|{prediction.x!r}|{prediction.y!r}"
    return hashlib.sha256(f"povagent-judged-item-2|{identity}|{key}|{point}".encode()).hexdigest()[:32]


class Judgement(BaseModel):
    """One judge's verdict on one prediction (a line of the judge's file)."""

    model_config = ConfigDict(frozen=True)

    #: the prediction judged: :func:`judged_item` of its run's identity, row key and prediction
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
    return _judgements_in(read_regular(path, MAX_DOCUMENT_BYTES, what="judgements file"))


def _judgements_in(data: bytes) -> list[Judgement]:
    out: list[Judgement] = []
    for line in data.splitlines():
        try:
            out.append(Judgement.model_validate(json.loads(line)))
        except (ValueError, RecursionError, ValidationError):
            continue
    return out


class JudgementJournal:
    """A judge's file, appended one fsynced line at a time, inside its folder only.

    ``root`` is the folder the judge named (followed: theirs to place); ``rel`` (``judgements``
    for the default folder beside the runs) and the file are below it and never followed as
    links, when read as when written."""

    def __init__(self, root: Path, judge: str, rel: str = "") -> None:
        self.root, self.rel = root, rel
        self.folder = root / rel if rel else root
        self.name = f"{judge}.jsonl"
        self.path = self.folder / self.name
        # a torn last line (a kill mid-write) is ended before the next line, so it stays alone
        data = self._bytes()
        self._torn = bool(data) and not data.endswith(b"\n")

    def _bytes(self) -> bytes:
        try:
            return read_inside(self.root, f"{self.rel}/{self.name}" if self.rel else self.name, MAX_DOCUMENT_BYTES, what="judgements file")
        except FileNotFoundError:
            return b""

    def read(self) -> list[Judgement]:
        """What the judge has judged so far."""
        return _judgements_in(self._bytes())

    def append(self, judgement: Judgement) -> None:
        """Make ``judgement`` durable: written, flushed and fsynced before this returns."""
        with ConfinedFolder(self.root, self.rel) as folder, folder.open_append(self.name, binary=True) as f:
            f.write((("\n" if self._torn else "") + judgement.model_dump_json() + "\n").encode())
            f.flush()
            os.fsync(f.fileno())
        self._torn = False
