"""The format versions of what a run folder holds, and the one step that upgrades each older shape.

A results row (``results.jsonl``) and a run's ``summary.json`` carry ``format_version``: the
shape they were written in. Readers see only the current shape: the one reader of each file
(:func:`povagent.results.rows.iter_rows` and what is built on it; the report's reader of
``summary.json``) passes what it read through :func:`upgrade_row` or :func:`upgrade_summary`
first, so what older versions wrote is handled here, once, and nowhere else.

- **Format 0** is everything written before rows carried a version (every release up to and
  including 0.1.0, and this tree until the field came). It was not one shape: fields arrived
  one after another, and a row of each era holds exactly the fields of its era (a row is
  written with every field, ``null`` included), so which of :data:`ROW_STEPS` a row still
  needs is told by the fields it lacks, never guessed from its content. Each step adds what
  one era lacked, only where it is absent.
- **Format 1** (:data:`ROW_FORMAT`, :data:`SUMMARY_FORMAT`) is the current shape: the fields
  of :class:`~povagent.results.rows.ResultRow` and :class:`~povagent.run.summary_model.RunSummary`.

A version newer than this release is refused with one line naming the file and the field:
povagent cannot know what a later release meant by a field, and reading it as today's shape
would quietly change a score. A version that is not a whole number is refused likewise.

What an upgrade cannot give a row: a fact that was never recorded. A lenient parser's row of
format 0 from before official readings carries none (``official_reading`` is ``null``, and the
summaries count it in ``rows_without_reading``; ``povagent rescore RUN --parser official``
makes the reading from the dataset); a row from before requests were kept has ``null``
prompts. Those stay ``null``: the current shape already says "not recorded" with it.

Adding a version: bump the constant, write the step from the previous version as a function of
the parsed JSON, append it to the steps, and add a fixture of the old shape to
``tests/fixtures/row_formats``. This module only transforms parsed JSON: it reads no file and
imports no row model.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from povagent.errors import PredictionsError

#: The version of the rows this release writes (``format_version`` of each ``results.jsonl`` line).
ROW_FORMAT = 1
#: The version of the ``summary.json`` this release writes.
SUMMARY_FORMAT = 1
#: The field that holds the version, in a row and in a summary.
FIELD = "format_version"


@dataclass(frozen=True)
class Step:
    """How data of format ``version`` becomes format ``version + 1``: ``shape`` says in a line
    what that format was; ``eras`` are its parts, oldest first, each a function of the parsed
    JSON (changed in place) whose docstring says when its fields arrived and what a row without
    them gets."""

    version: int
    shape: str
    eras: tuple[Callable[[dict[str, Any]], None], ...] = ()

    def apply(self, data: dict[str, Any]) -> None:
        """Upgrade ``data`` (parsed JSON of format :attr:`version`) by one version, in place."""
        for era in self.eras:
            era(data)


# -- rows of format 0, era by era -----------------------------------------------------------------
def _exchanges(row: dict[str, Any]) -> list[dict[str, Any]]:
    exchanges = row.get("exchanges")
    return [e for e in exchanges if isinstance(e, dict)] if isinstance(exchanges, list) else []


def _official_readings(row: dict[str, Any]) -> None:
    """Rows of the first days (2026-11-22) lack ``official_reading``: none was recorded."""
    row.setdefault("official_reading", None)


def _model_and_prompts(row: dict[str, Any]) -> None:
    """Rows before 2026-11-25 name no model (``model`` ``""``, unknown: a report names the run by
    its config's model) and keep no request (``exchanges[].prompt`` ``null``)."""
    row.setdefault("model", "")
    row.setdefault("profile", None)
    for exchange in _exchanges(row):
        exchange.setdefault("prompt", None)


def _labels_answer_types_whole_prompts(row: dict[str, Any]) -> None:
    """Rows before 2026-11-29 (release 0.1.0's among them) carry no ``label``, an untyped
    prediction (``answer_type`` and ``value`` ``null``: its x/y are what it answered) and every
    request's prompt whole (``prompt_continues`` false)."""
    row.setdefault("label", None)
    prediction = row.get("prediction")
    if isinstance(prediction, dict):
        prediction.setdefault("answer_type", None)
        prediction.setdefault("value", None)
    for exchange in _exchanges(row):
        exchange.setdefault("prompt_continues", False)


def _categories(row: dict[str, Any]) -> None:
    """Rows before 2026-12-07 record no question ``category``: a multiple-choice row's is the
    first non-empty ``category`` among its scores (by scorer name), which its choice scorer
    wrote when the answer was scored; ``main_category`` is ``null``."""
    if "category" not in row:
        scores = row.get("scores")
        scores = scores if isinstance(scores, dict) else {}
        found = (fields.get("category") for _, fields in sorted(scores.items()) if isinstance(fields, dict))
        row["category"] = next((c for c in found if isinstance(c, str) and c), None)
    row.setdefault("main_category", None)


#: The steps of a row, oldest first: ``ROW_STEPS[v]`` turns a row of format ``v`` into ``v + 1``.
ROW_STEPS: tuple[Step, ...] = (
    Step(0, "rows without a version (release 0.1.0's and every other before format 1), written in four eras",
         (_official_readings, _model_and_prompts, _labels_answer_types_whole_prompts, _categories)),
)


# -- summaries --------------------------------------------------------------------------------------
#: The steps of a ``summary.json``, oldest first (as :data:`ROW_STEPS`). Format 0's step changes
#: nothing: every section added since summaries were first written (``metrics``,
#: ``official_parse``, ``pipeline``, ...) is optional, and a summary without one has none.
SUMMARY_STEPS: tuple[Step, ...] = (Step(0, "summaries without a version: read as they are, sections added since absent"),)


# -- applying them --------------------------------------------------------------------------------
def version_of(data: Mapping[str, Any], current: int, where: str, what: str) -> int:
    """The format version ``data`` says it has (``0`` when it says none); a
    :class:`PredictionsError` naming ``where`` and the field when it is not a version this
    release reads (a later release's, or not a whole number)."""
    version = data.get(FIELD, 0)
    if isinstance(version, bool) or not isinstance(version, int) or version < 0:
        raise PredictionsError(f"{where}: {FIELD}: {version!r} is not a format version (a whole number from 0); a damaged or hand-edited {what}")
    if version > current:
        raise PredictionsError(
            f"{where}: {FIELD}: {version} is newer than this povagent reads ({what} formats up to {current}); "
            f"read it with the povagent release that wrote it, or a later one"
        )
    return version


def _upgraded(data: Any, steps: tuple[Step, ...], current: int, where: str, what: str) -> Any:
    if not isinstance(data, dict):
        return data  # not an object: the model's own check names what is wrong
    version = version_of(data, current, where, what)
    for step in steps[version:]:
        step.apply(data)
    data[FIELD] = current
    return data


def upgrade_row(data: Any, where: str) -> Any:
    """A results row's parsed JSON in the current shape (changed in place): each step from the
    version it says (``0`` when none) to :data:`ROW_FORMAT`. ``where`` names the file and line
    in the one-line refusal of a newer (or damaged) version. Anything but an object is returned
    as it is, for the row model to refuse."""
    return _upgraded(data, ROW_STEPS, ROW_FORMAT, where, "row")


def upgrade_summary(data: Any, where: str) -> Any:
    """A ``summary.json``'s parsed JSON in the current shape (as :func:`upgrade_row`)."""
    return _upgraded(data, SUMMARY_STEPS, SUMMARY_FORMAT, where, "summary")
