"""What a summary reads of one row: its score by the run's ``normalized_l2`` scorer
(:func:`scored_row`), the fields of the scorers that follow no protocol (:func:`plugin_scores`)
and its diagnosis (:func:`diagnosed_row`). A run summary keeps these
(:mod:`povagent.run.summary_table`), and the report reads rows the same way.

Pure: a row in, values out.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from typing import Any

from povagent.results.evaluations import official_parse_error
from povagent.results.rows import ResultRow, RowStatus
from povagent.scoring.breakdown import ScoredRow
from povagent.scoring.diagnostics_breakdown import DiagnosedRow
from povagent.scoring.score_protocols import diagnosing_scorers


def scored_row(row: ResultRow, scorer: str | None) -> ScoredRow:
    """The fields a summary needs, from the row's score by ``scorer``, the run's ``normalized_l2``
    scorer (non-answers count as such; ``None``: the run has none, and no row is answered). A row
    of a multiple-choice question (it records a category, or its parse chose an option) asks no
    point: the point breakdown leaves it out."""
    return ScoredRow(*scored_values(row, scorer))


def scored_values(row: ResultRow, scorer: str | None) -> tuple[Any, ...]:
    """:func:`scored_row`'s fields, in :class:`ScoredRow`'s order, as a tuple (a summary keeps
    them in columns, and compares a row's with its official reading's, without the object)."""
    score = (row.scores.get(scorer) if scorer is not None else None) or {}
    answered = row.status is RowStatus.ANSWERED and bool(score.get("answered"))
    asks_point = row.category is None and (row.parse is None or row.parse.choice is None)
    return (
        sys.intern(row.condition),  # one string per label, not one per row a summary keeps
        sys.intern(row.direction),
        answered,
        score.get("l2") if answered else None,
        score.get("gt_in_frame") if answered else None,
        score.get("l2_strict") if answered else None,
        row.run,
        score.get("error_x") if answered else None,
        score.get("error_y") if answered else None,
        asks_point and official_parse_error(row) is not None,
        asks_point,
    )


def plugin_scores(scores: Mapping[str, Any], protocols: Mapping[str, str]) -> tuple[tuple[str, tuple[tuple[str, float], ...]], ...]:
    """For every scorer of a row that follows no protocol (``protocols``: ``{scorer: protocol}``;
    a protocol's fields have sections of their own), its true/false and number fields (text and
    lists left out)."""
    # a plain dict is told from other mappings first: the ABC check costs more than the rest
    return tuple(
        [
            (name, tuple([(k, v) for k, v in fields.items() if type(v) in _NUMBER_TYPES or isinstance(v, (bool, int, float))]))
            for name, fields in sorted(scores.items())
            if name not in protocols and (type(fields) is dict or isinstance(fields, Mapping))
        ]
    )


#: The types :func:`plugin_scores` keeps, told by identity before ``isinstance`` (subclasses).
_NUMBER_TYPES = frozenset({bool, int, float})


def diagnosed_row(row: ResultRow, error_scorer: str | None, by: Mapping[str, str] | None = None) -> DiagnosedRow | None:
    """The fields of the scorers diagnosing an answered row (``failure_step`` and
    ``relation_hit``, :func:`~povagent.scoring.score_protocols.diagnosing_scorers`, or ``by`` when the
    caller asked it already), with its error by ``error_scorer`` (the run's ``normalized_l2``
    scorer), or ``None`` when neither scored it."""
    if row.status != RowStatus.ANSWERED:  # a StrEnum: a plain string from model_construct compares too
        return None
    if by is None:
        by = diagnosing_scorers()
    diagnose = row.scores.get(by.get("failure_step", ""))
    relation = row.scores.get(by.get("relation_hit", ""))
    if diagnose is None and relation is None:  # neither scored it (most rows of most runs): no ABC check
        return None
    diagnose = diagnose if isinstance(diagnose, Mapping) and diagnose.get("answered") is True else None
    relation = relation if isinstance(relation, Mapping) and relation.get("answered") is True else None
    if diagnose is None and relation is None:
        return None
    official = (row.scores.get(error_scorer) if error_scorer is not None else None) or {}
    l2 = official.get("l2") if isinstance(official, Mapping) else None
    step = diagnose.get("step") if diagnose is not None else None
    vote = diagnose.get("nearer_egocentric") if diagnose is not None else None
    hit = relation.get("success") if relation is not None else None
    return DiagnosedRow(
        instance_id=row.instance_id,
        condition=str(row.condition),
        direction=str(row.direction),
        l2=float(l2) if isinstance(l2, (int, float)) and not isinstance(l2, bool) else None,
        step=step if isinstance(step, str) else None,
        nearer_egocentric=vote if isinstance(vote, bool) else None,
        relation=hit if isinstance(hit, bool) else None,
    )
