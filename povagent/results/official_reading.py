"""The official reading of an answer, kept beside a lenient parser's: paper numbers stay in sight.

A lenient parser (``json``, ``rescale-1000``, ``cot``, the native formats) repairs answers the
official runner leaves unanswered or reads differently, so its numbers are not the paper's. A row
parsed with one therefore also records how the official runner reads the same answer
(:class:`~povagent.results.rows.OfficialReading`: that parse and its scores), and every summary of such rows carries the
official reading's response rate and mean beside the repaired ones (``official_parse``).

Why at run time, in the row: the runner already holds the answer, the asked schema, the instance
and the scorers, and the official parse costs tens of microseconds (when it reads the same point
as the lenient parser, its scores are the lenient ones, not recomputed). Summaries, reports and
``povagent score`` then read it without the dataset or the strategy, a resumed run keeps every
earlier row's reading, and ``povagent rescore`` writes a fresh one for each row it re-parses.
Format 0 rows of povagent's first days carry none (an upgrade cannot make one:
:mod:`povagent.results.upgrade`): summaries count them (``rows_without_reading``) rather than
mix repaired numbers in; ``povagent rescore RUN --parser official`` gives such a run its
official numbers offline.

The reading's record is part of the row format (:class:`~povagent.results.rows.OfficialReading`);
this module makes and applies it. It never calls a model, reads a run folder or writes a file.
"""

from __future__ import annotations

import copy
import math
from typing import Any, Callable, Iterable, Mapping, Sequence

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.results.plugin_errors import parse_or_unparseable
from povagent.results.rows import OfficialReading, Prediction, ResultRow, RowStatus

#: The parser that reads the asked JSON answer as the official runner does.
OFFICIAL_PARSER = "official"


def official_counterpart(parser: Any) -> str | None:
    """The name of the parser giving the official reading of what ``parser`` reads, or ``None``
    when ``parser`` itself reads as the official runner does (``reproduces_official``).

    A parser names its counterpart in ``official_reading`` (RoboPoint's is
    ``robopoint-official``); any other parser, a third-party one too, has ``official``.
    """
    if getattr(parser, "reproduces_official", False):
        return None
    return getattr(parser, "official_reading", OFFICIAL_PARSER)


def scores_alike(a: ParsedAnswer, b: ParsedAnswer) -> bool:
    """Whether two parses give the same scores (same answer, frame, point and points)."""
    return (a.answered, a.selected_image, a.x, a.y, a.points) == (b.answered, b.selected_image, b.x, b.y, b.points)


def read_officially(
    official_parser: Any,
    name: str,
    text: str,
    spec: AnswerSpec,
    parse: ParsedAnswer | None,
    scores: dict[str, dict[str, Any]],
    score: Callable[[ParsedAnswer], dict[str, dict[str, Any]]],
) -> OfficialReading:
    """The official reading of ``text``, beside the lenient ``parse`` and its ``scores``.

    ``score(parsed)`` scores a parse with the run's scorers; it is only called when the official
    parse answers differently from the lenient one. An unanswered official parse has no scores,
    as the runner leaves a parse error unscored. Never raises.
    """
    official = parse_or_unparseable(official_parser, text, spec)  # a raising parser: no answer
    if not official.answered:
        return OfficialReading(parser=name, parse=official)
    if parse is not None and scores_alike(official, parse):
        return OfficialReading(parser=name, parse=official, scores=scores)
    return OfficialReading(parser=name, parse=official, scores=score(official))


#: Built-in parsers that read answers as the official runner does.
OFFICIAL_PARSERS = frozenset({OFFICIAL_PARSER, "robopoint-official"})


def officially_read(row: Any) -> Any:
    """``row`` as its official reading scores it: itself when it holds no separate reading.

    The prediction is the official parse's point and frame index (the frame is found again by
    that index when the row is scored)."""
    reading = row.official_reading
    if reading is None:
        return row
    parse = reading.parse
    update = {
        "parser": reading.parser,
        "parse": parse,
        "scores": reading.scores,
        "status": _official_status(parse),
        "prediction": _official_prediction(parse),
        "official_reading": None,
    }
    if type(row) is not ResultRow:
        return row.model_copy(update=update)
    # ``model_copy(update=...)``'s copy, made directly: a summary reads every row this way, and
    # pydantic's generic copy (three ``copy.copy`` calls) was most of its cost
    copied = ResultRow.__new__(ResultRow)
    _set(copied, "__dict__", {**row.__dict__, **update})
    _set(copied, "__pydantic_fields_set__", row.__pydantic_fields_set__ | update.keys())
    _set(copied, "__pydantic_extra__", None if row.__pydantic_extra__ is None else dict(row.__pydantic_extra__))
    _set(copied, "__pydantic_private__", None if row.__pydantic_private__ is None else dict(row.__pydantic_private__))
    return copied


_set = object.__setattr__


def _official_status(parse: ParsedAnswer) -> RowStatus:
    """The status of a row as its official parse reads it."""
    return RowStatus.ANSWERED if parse.answered else RowStatus.PARSE_ERROR


def _official_prediction(parse: ParsedAnswer) -> Prediction:
    """The prediction of a row as its official parse reads it: the parse's point and frame index."""
    return Prediction(selected_image=parse.selected_image, x=parse.x, y=parse.y) if parse.answered else Prediction()


class OfficialView:
    """:func:`officially_read` of a row that holds a reading, read without copying the row: the
    fields the reading replaces are its own, every other is the row's (a run's summary reads
    each row's official fields once, and the copy of 35 fields was a fifth of that read)."""

    __slots__ = ("_row", "parser", "parse", "scores", "status", "key", "condition", "direction", "run", "category", "error_type", "error_message")

    #: the reading read is the row's reading: none is left beside it
    official_reading = None

    def __init__(self, row: Any, reading: OfficialReading) -> None:
        parse = reading.parse
        self._row, self.parser, self.parse, self.scores = row, reading.parser, parse, reading.scores
        self.status = _official_status(parse)
        # the row's own fields a summary reads, held here: no lookup through __getattr__
        self.key, self.condition, self.direction, self.run = row.key, row.condition, row.direction, row.run
        self.category, self.error_type, self.error_message = row.category, row.error_type, row.error_message

    @property
    def prediction(self) -> Prediction:
        """The official parse's point and frame index (as :func:`officially_read` makes it)."""
        return _official_prediction(self.parse)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._row, name)


def official_view(row: Any) -> Any:
    """:func:`officially_read` for reading only: ``row`` itself when it holds no separate
    reading, else an :class:`OfficialView` of it (the same field values, no copy made)."""
    reading = row.official_reading
    return row if reading is None else OfficialView(row, reading)


def official_rows(rows: Iterable[Any]) -> tuple[list[Any], list[str]]:
    """Rows as their official readings score them, and warnings: how many answered rows were
    parsed leniently without recording a reading (those are kept as parsed: repaired numbers),
    and which rows hold a NaN coordinate."""
    out, unread = [], []
    for row in rows:
        if row.official_reading is None and row.parser not in OFFICIAL_PARSERS and row.parse is not None:
            unread.append(row.key)
        out.append(officially_read(row))
    warnings = []
    if unread:
        parsers = sorted({r.parser for r in out if r.key in set(unread)})
        warnings.append(
            f"{len(unread)} row(s) parsed with {', '.join(parsers)} carry no official reading (format 0 rows "
            f"of povagent's first days) and are scored as parsed, i.e. repaired: for paper-comparable numbers "
            f"run povagent rescore RUN --parser official"
        )
    nan_note = nan_warning(nan_rows(out))
    if nan_note:
        warnings.append(nan_note)
    return out, warnings


def official_parse_breakdown(
    scored: Sequence[Any], parser: str, without_reading: int, computed: Mapping[str, Any] | None = None
) -> dict[str, Any]:
    """The ``official_parse`` section of a summary: the official reading's breakdown (one
    :class:`~povagent.scoring.breakdown.ScoredRow` per row that has a reading or no answer at
    all, aggregated as the main breakdown is), the parser that gave it, and how many rows with
    an answer lack a reading: those are left out, so the section is then incomplete and says so.
    ``computed``: the breakdown of ``scored`` when it is already at hand (every row read as
    parsed: the main breakdown), copied instead of computed again."""
    from povagent.scoring.breakdown import breakdown

    numbers = copy.deepcopy(dict(computed)) if computed is not None else breakdown(scored)
    return {"parser": parser, "rows_without_reading": without_reading, **numbers}


def nan_rows(rows: Iterable[Any]) -> list[str]:
    """Keys of rows whose (official) parse holds a NaN coordinate: the official scorer counts
    such a row answered with a NaN error, which makes every mean holding it NaN."""
    return [row.key for row in rows if holds_nan(row.parse)]


def holds_nan(parse: Any) -> bool:
    """Whether ``parse`` (a row's parse, or ``None``) holds a NaN coordinate (see :func:`nan_rows`)."""
    if parse is None:
        return False
    x, y = parse.x, parse.y
    return (isinstance(x, float) and math.isnan(x)) or (isinstance(y, float) and math.isnan(y))


def nan_warning(keys: Sequence[str]) -> str | None:
    """The warning naming rows with a NaN coordinate, or ``None`` when there are none."""
    if not keys:
        return None
    shown = ", ".join(keys[:10]) + (f" and {len(keys) - 10} more" if len(keys) > 10 else "")
    return (
        f"{len(keys)} row(s) answered with a NaN coordinate, as the official runner records them: {shown}. "
        "The official scorer counts them answered with a NaN error, which makes its mean of any slice "
        "holding them NaN"
    )
