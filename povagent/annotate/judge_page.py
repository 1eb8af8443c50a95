"""Judge mode: the predictions of one or more runs, drawn on their frames, judged blind.

The runs are read as the report reads them (:func:`povagent.report.collect.collect`) and their
dataset as the report loads it; every answered prediction in a dataset frame becomes an item.
Items are shown in an order shuffled per judge (seeded by the name and a seed), with nothing
that tells the system (no run name, no model, no instance id), and the ones the judge's file
already holds are skipped: a judge session resumes where it stopped. The frame is found here
from the dataset (item number and image index from the page, never a path).
"""

from __future__ import annotations

import hashlib
import io
import random
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from PIL import Image

from povagent.annotate.desk import AnswerRefused
from povagent.errors import ConfigError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular
from povagent.results.judgements import MAX_NOTE_CHARS, VERDICTS, Judgement, JudgementJournal, judged_item, run_identity
from povagent.scoring.normalized_l2 import scoring_frame

MEDIA_TYPES = {"PNG": "image/png", "JPEG": "image/jpeg", "WEBP": "image/webp"}


@dataclass(frozen=True)
class JudgeItem:
    """One prediction to judge: where it is drawn, what sentence it answers, whose it is."""

    item: str
    frame_file: Path
    x: float
    y: float
    sentence: str
    system: str
    run_name: str
    key: str
    instance_id: str
    condition: str


@dataclass(frozen=True)
class Predictions:
    """The items to judge and the dataset their frames belong to (held: a real-world set's
    letterboxed frames live as long as its dataset does)."""

    items: list[JudgeItem]
    dataset: Any


def judge_items(paths: list[Path]) -> Predictions:
    """Every answered prediction of the runs (or sweeps) at ``paths`` that lies in a dataset frame
    (an answer in an active episode's rendered view is left out: its image is no dataset's), each
    named by its run's identity and row key (:func:`~povagent.results.judgements.judged_item`)."""
    from povagent.report.baseline_systems import is_baseline_system
    from povagent.report.collect import collect
    from povagent.report.paper_protocol import outside_paper_protocol
    from povagent.report.run_sets import load_collection_dataset

    collection = collect(paths)
    dataset, note = load_collection_dataset(collection, None)
    if dataset is None:
        raise ConfigError(f"{paths[0]}: the runs' dataset is needed to show their frames: {note}")
    items: list[JudgeItem] = []
    for run in collection.runs:
        identity = run_identity(run.folder)
        screened = not is_baseline_system(run.axes, run.system)  # the rows the report reads, as collect() screens them
        for row in run.rows:
            p = row.prediction
            # an answer given in a rendered view (the active mode) lies in no dataset frame: not drawn here
            if p.x is None or p.y is None or (row.parse is not None and row.parse.camera is not None):
                continue
            if screened and outside_paper_protocol(row.strategy, str(row.condition)):
                continue
            instance = dataset.instance(row.instance_id)
            frame = scoring_frame(instance, p.selected_image, p.image_path) if instance is not None else None
            if frame is None or not getattr(frame, "file", None):
                continue
            items.append(
                JudgeItem(
                    judged_item(identity, row.key, p),
                    Path(frame.file),
                    float(p.x),
                    float(p.y),
                    row.sentence,
                    run.system,
                    run.name,
                    row.key,
                    row.instance_id,
                    str(row.condition),
                )
            )
    return Predictions(items, dataset)


class JudgePage:
    """One judge's session (a :class:`~povagent.annotate.server.PageApp`)."""

    def __init__(self, predictions: Predictions, journal: JudgementJournal, judge: str, seed: int = 0) -> None:
        self.judge, self.journal = judge, journal
        self.predictions = predictions
        digest = hashlib.sha256(f"{judge}|{seed}".encode()).digest()
        self.items = sorted(predictions.items, key=lambda i: i.item)
        random.Random(int.from_bytes(digest[:8], "big")).shuffle(self.items)
        judged = {j.item for j in journal.read()}
        self._left = [i for i in self.items if i.item not in judged]
        self._done = len(self.items) - len(self._left)
        self._lock = threading.Lock()
        self._shown_at: float | None = None
        self._finished_at = time.monotonic()

    @property
    def total(self) -> int:
        """How many predictions there are to judge."""
        return len(self.items)

    def state_finished(self) -> bool:
        """Whether every prediction is judged (and the page has had a moment to say so)."""
        with self._lock:
            return not self._left and time.monotonic() - self._finished_at > 2.0

    def _current(self) -> JudgeItem | None:
        return self._left[0] if self._left else None

    def state(self) -> dict[str, Any]:
        """The prediction to judge (sentence, frame, point), and progress."""
        with self._lock:
            item = self._current()
            question = None
            if item is not None:
                if self._shown_at is None:
                    self._shown_at = time.monotonic()
                width, height = self._frame(item)[2]
                question = {
                    "number": self._done,
                    "parts": [{"text": item.sentence}, {"image": 0, "label": "the answered frame", "width": width, "height": height}],
                    "choices": [],
                    "point": {"image": 0, "x": item.x, "y": item.y},
                }
            return {"mode": "judge", "who": self.judge, "done": self._done, "total": len(self.items), "finished": item is None, "question": question}

    @staticmethod
    def _frame(item: JudgeItem) -> tuple[bytes, str, tuple[int, int]]:
        """The frame's bytes (read through the confined reader), media type and size."""
        data = read_regular(item.frame_file, MAX_IMAGE_FILE_BYTES, what="image")
        with Image.open(io.BytesIO(data)) as im:
            return data, MEDIA_TYPES.get(im.format or "", "application/octet-stream"), im.size

    def image(self, number: int, index: int) -> tuple[bytes, str] | None:
        """The frame of the prediction being judged."""
        with self._lock:
            item = self._current()
            if item is None or number != self._done or index != 0:
                return None
        data, media, _ = self._frame(item)
        return data, media

    def post(self, action: str, body: dict[str, Any]) -> dict[str, Any]:
        """``judge``: the verdict (and note) on the prediction shown; replies once it is durable."""
        if action != "judge":
            raise KeyError(action)
        verdict, note = body.get("verdict"), body.get("note", "")
        if not isinstance(verdict, str) or verdict not in VERDICTS:
            raise AnswerRefused(f"verdict must be one of {', '.join(VERDICTS)}")
        if not isinstance(note, str) or len(note) > MAX_NOTE_CHARS:
            raise AnswerRefused(f"note must be text of at most {MAX_NOTE_CHARS} characters")
        with self._lock:
            item = self._current()
            if item is None or body.get("question") != self._done:
                raise AnswerRefused("that prediction is not the one shown (judged already?)")
            seconds = round(time.monotonic() - (self._shown_at or time.monotonic()), 3)
            self.journal.append(
                Judgement(
                    item=item.item,
                    judge=self.judge,
                    verdict=verdict,
                    note=note,
                    seconds=seconds,
                    system=item.system,
                    run_name=item.run_name,
                    key=item.key,
                    instance_id=item.instance_id,
                    condition=item.condition,
                )
            )
            self._left.pop(0)
            self._done += 1
            self._shown_at = None
            self._finished_at = time.monotonic()
        return {"saved": True}
