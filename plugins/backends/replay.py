"""The ``replay`` backend: answers from an earlier run, or from an official predictions file.

``path`` is one of:

* a run folder (holding ``results.jsonl``) or a ``results.jsonl`` file: each request is
  answered with the recorded raw answer of the same (instance, run), so a run can be re-parsed
  and re-scored with another parser or scorer without calling a model;
* an official predictions file or folder (see :mod:`povagent.results.official_format`): the answer is
  JSON synthesized from ``predicted_x``/``predicted_y`` and, for A/B, the index of the frame
  whose ``image_path`` is ``predicted_image``. A row without a point answers nothing (an empty
  text: a non-response, as in the official scoring), a row whose frame is missing or unknown
  answers without ``selected_image`` (unanswered, as officially). An official file holds one
  run: with several rows for one instance, run ``r`` takes the ``r``-th; with one, every run
  takes it.

A request with no recorded answer raises ``PermanentBackendError("no recorded answer for
<key>")``. The file is read once, when the backend is made; nothing is written.
"""

from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path
from typing import Any, ClassVar, Mapping

from povagent import hookimpl
from povagent.dataset.instances import row_key
from povagent.errors import PredictionsError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, Usage
from povagent.interfaces import Backend, PermanentBackendError
from povagent.results.official_format import OfficialPrediction, read_official_predictions
from povagent.results.rows import ResultRow, iter_rows
from povagent_plugins.backends.baselines import request_run

RESULTS_FILE = "results.jsonl"


def _results_file(path: Path) -> Path | None:
    """Our results file for ``path`` (a run folder or the file itself), else None."""
    if path.is_dir() and (path / RESULTS_FILE).is_file():
        return path / RESULTS_FILE
    if path.is_file() and path.suffix == ".jsonl":
        with open(path, encoding="utf-8") as fh:
            first = fh.readline()
        try:
            ResultRow.model_validate_json(first)
        except ValueError:
            return None  # JSON lines of official rows
        return path
    return None


class ReplayBackend(Backend):
    """Answers each request with a recorded answer (our results, or official predictions)."""

    cacheable: ClassVar[bool] = False

    def __init__(self, path: str) -> None:
        self.path = Path(path).expanduser()
        if not self.path.exists():
            raise PredictionsError(f"backend 'replay': option 'path': {self.path} does not exist")
        self._raw_by_key: dict[str, str | None] = {}
        self._status_by_key: dict[str, str] = {}
        self._official: dict[str, list[OfficialPrediction]] = defaultdict(list)
        results = _results_file(self.path)
        self.source = "results" if results is not None else "official"
        if results is not None:
            for row in iter_rows(results):  # when a key repeats, the last row wins (a re-run)
                self._raw_by_key[row.key] = row.raw_response
                self._status_by_key[row.key] = f"{row.status}: {row.error_message or ''}".rstrip(": ")
            if not self._raw_by_key:
                raise PredictionsError(f"{results}: holds no complete result rows")
        else:
            for pred in read_official_predictions(self.path):
                self._official[pred.instance_id].append(pred)

    def identity(self) -> Mapping[str, Any]:
        """Name and source path."""
        return {"backend": "replay", "path": str(self.path.resolve())}

    def __len__(self) -> int:
        """Number of recorded answers."""
        return len(self._raw_by_key) + sum(len(v) for v in self._official.values())

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """The recorded answer for this (instance, run)."""
        if request.instance is None:
            raise PermanentBackendError("replay needs request.instance to find the recorded answer; the strategy sent none")
        run = request_run(request)
        key = row_key(request.instance.id, run)
        text = self._recorded_text(request, key) if self.source == "results" else self._official_text(request, run, key)
        return Response(text=text, usage=Usage(), latency_s=0.0, model="replay")

    def _recorded_text(self, request: Request, key: str) -> str:
        if key not in self._raw_by_key:
            raise PermanentBackendError(f"no recorded answer for {key}")
        raw = self._raw_by_key[key]
        if raw is None:
            raise PermanentBackendError(f"no recorded answer for {key} (the recorded row is {self._status_by_key[key]})")
        return raw

    def _official_text(self, request: Request, run: int, key: str) -> str:
        rows = self._official.get(request.instance.id)  # type: ignore[union-attr]  # replayed requests always carry their instance
        if not rows:
            raise PermanentBackendError(f"no recorded answer for {key}")
        if len(rows) == 1:
            pred = rows[0]
        elif run < len(rows):
            pred = rows[run]
        else:
            raise PermanentBackendError(f"no recorded answer for {key} ({len(rows)} rows for this instance)")
        return official_answer_text(request, pred)


def official_answer_text(request: Request, pred: OfficialPrediction) -> str:
    """The JSON answer an official row stands for ('' when it holds no point)."""
    if not pred.has_point:
        return ""
    doc: dict[str, Any] = {}
    if request.answer.asks_frame and request.instance is not None:
        frame = request.instance.frame_by_path(pred.predicted_image) if pred.predicted_image else None
        if frame is not None:
            doc["selected_image"] = frame.index
    doc["x"] = pred.predicted_x
    doc["y"] = pred.predicted_y
    return json.dumps(doc)


@hookimpl
def register_backends(register) -> None:
    """Contribute the replay backend."""
    register("replay", ReplayBackend, description="Answers from an earlier run's results or an official predictions file")
