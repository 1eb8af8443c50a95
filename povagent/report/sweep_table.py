"""The sweep command's tables, as rows of text: what a dry run still has to do, and each
finished cell's scores (with the official parse's numbers beside a lenient cell's, and the
success rate of a real-world set's cell).

Only table contents: ``povagent sweep`` lays them out on the console
(:func:`povagent.cli.console_width.fitted_table`); nothing here prints or reads a file.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import TYPE_CHECKING

from povagent.results.official_reading import OFFICIAL_PARSERS
from povagent.run.sweep_estimate import DryRunCell

if TYPE_CHECKING:
    from povagent.run.summary_model import Cell, RunSummary, SuccessBreakdown, SuccessCell

#: A table's columns: (heading, ``label`` or ``number``).
Columns = list[tuple[str, str]]
#: Whether a cell's summary holds an official reading whose numbers differ from the cell's own.
RepairChanged = Callable[["RunSummary"], bool]


def percent(value: float | None) -> str:
    """A rate as a percentage with one decimal, ``-`` when there is none."""
    return "-" if value is None else f"{100 * value:.1f}%"


def rate(cell: SuccessCell) -> str:
    """A success cell's success rate as :func:`percent`."""
    return percent(cell.success_rate)


def mean_l2(cell: Cell) -> str:
    """A cell's mean L2 with three decimals, ``-`` when there is none."""
    return "-" if cell.mean_l2 is None else f"{cell.mean_l2:.3f}"


def official_cells(summary: RunSummary, repair_changed: RepairChanged) -> tuple[str, str]:
    """A sweep cell's official-parse columns: its numbers when its repair changed one, ``=`` when
    the cell reads officially itself or its repair changed no number, ``?`` when a lenient cell
    recorded no official reading."""
    official = summary.official_parse
    if official is not None and repair_changed(summary):
        return mean_l2(official.overall), percent(official.overall.response_rate)
    if official is not None:
        return "=", "="
    parser = summary.pipeline.parser if summary.pipeline is not None else None
    mark = "=" if parser in OFFICIAL_PARSERS else "?"
    return mark, mark


def dry_run_table(plans: Iterable[DryRunCell]) -> tuple[Columns, list[list[str]], list[str]]:
    """The dry run's columns, rows (a cell, then each turn of a multi-turn strategy, then the
    total, bold) and notes (a turn taken only sometimes is counted for every key: an upper
    bound; a strategy whose later turns are unknown)."""
    rows: list[list[str]] = []
    totals = [0, 0, 0, 0, 0]
    notes: list[str] = []
    for c in plans:
        vals = [c.n_total, c.n_done, c.requests, c.prompt_tokens, c.max_completion_tokens]
        totals = [a + b for a, b in zip(totals, vals)]
        rows.append([c.name, *(f"{v:,}" for v in vals)])
        if len(c.turns) > 1:  # a multi-turn strategy: each turn's requests and tokens under the cell
            for t in c.turns:
                rows.append([f"  turn {t.turn}" + ("*" if t.note else ""), "", "", *(f"{v:,}" for v in (t.requests, t.prompt_tokens, t.max_completion_tokens))])
                if t.note and f"turn {t.turn}: {t.note} (counted for every key)" not in notes:
                    notes.append(f"turn {t.turn}: {t.note} (counted for every key)")
        if not c.turns_declared:
            notes.append(f"{c.name}: its strategy overrides solve() without plan_turns(): only the first turn is counted")
    rows.append(["[bold]total", *(f"[bold]{v:,}" for v in totals)])
    columns = [("cell", "label")] + [(h, "number") for h in ("keys", "done", "requests to make", "~prompt tokens", "<= completion tokens")]
    return columns, rows, notes


def sweep_table(
    summaries: Mapping[str, RunSummary], successes: Mapping[str, SuccessBreakdown | None], repair_changed: RepairChanged
) -> tuple[Columns, list[list[str]]]:
    """The finished cells' columns and rows, in ``summaries``' order: mean L2, response rate,
    answered of total; the official parse's numbers when any cell's named repair changed an
    answer (``repair_changed``); the success rate when any cell is a real-world set's
    (``successes``: its success breakdown)."""
    with_success = any(v is not None for v in successes.values())  # real-world sets
    # cells whose named repair changed an answer: the official parse's numbers beside (``=``: the
    # cell reads officially, or its repair read every answer as the official parse does)
    with_official = any(repair_changed(s) for s in summaries.values())
    official_cols = ("official parse L2", "official parse resp.") if with_official else ()
    headers = ("mean L2", "resp. rate", "answered / total") + official_cols + (("success rate",) if with_success else ())
    rows = []
    for name, s in summaries.items():
        success = successes.get(name)
        if success is not None:
            # response and answered as the success scorer judged them: the official columns
            # of the summary count every row of a set without official GT as unanswered
            o = success.overall
            answered = "-" if o.n_answered is None else f"{o.n_answered} / {o.n_total}"
            rows.append([name, "-", percent(o.response_rate), answered, *(("-", "-") if with_official else ()), rate(o)])
            continue
        cell = s.overall
        total = s.rows.total if s.rows is not None else cell.n_total
        rows.append(
            [
                name,
                mean_l2(cell),
                percent(cell.response_rate),
                f"{cell.n} / {total}",
                *(official_cells(s, repair_changed) if with_official else ()),
                *(("-",) if with_success else ()),
            ]
        )
    return [("cell", "label")] + [(h, "number") for h in headers], rows
