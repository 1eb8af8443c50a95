"""The report table that keeps paper numbers beside repaired ones: systems parsed leniently.

A system whose runs were parsed with a lenient parser (``json``, ``rescale-1000`` ...) reports
repaired numbers in the main tables. This table puts, per condition, its mean error and response
rate beside those of the official parse of the same answers (recorded in each row, see
:mod:`povagent.results.official_reading`), both labelled, so that nobody compares a repaired
number with the paper by accident. Runs are aggregated as the main breakdown aggregates them.
Systems parsed officially are not listed, nor baselines (they write their answer, no model's
text is repaired), nor a system whose repair changed no answer (both sides would be the same
numbers); the table is absent when there is none to list.
"""

from __future__ import annotations

from povagent.dataset.release_models import Condition
from povagent.report.baseline_systems import is_baseline_system
from povagent.report.collect import Collection
from povagent.report.tables import Cell, Column, Row, Table
from povagent.results.official_reading import OFFICIAL_PARSERS, officially_read, scores_alike

KEY = "official_parse_beside"


def _repair_changed(row) -> bool:
    """Whether a named repair read ``row``'s answer otherwise than the official runner does;
    a lenient row without a reading (format 0: :mod:`povagent.results.upgrade`) counts too (its
    official side is unknown, and the table says how to obtain it)."""
    if row.official_reading is None:
        return row.parse is not None and row.parser not in OFFICIAL_PARSERS
    return row.parse is None or not scores_alike(row.official_reading.parse, row.parse)


def _repaired(run) -> bool:
    return not is_baseline_system(run.axes, run.system) and any(_repair_changed(r) for r in run.rows)


def official_beside_table(collection: Collection) -> Table | None:
    """Per lenient system and condition: mean L2 and response rate, repaired and official."""
    from povagent.run.summary_fields import scored_row
    from povagent.scoring.breakdown import breakdown

    by_system: dict[str, list] = {}
    scorer_of: dict[str, str] = {}  # each system's normalized_l2 scorer
    for run in collection.runs:
        if run.protocol == "normalized_l2" and _repaired(run):
            by_system.setdefault(run.system, []).extend(run.rows)
            scorer_of.setdefault(run.system, run.scorer)
    if not by_system:
        return None
    conditions = [c for c in (str(c) for c in Condition) if any(r.condition == c for rows in by_system.values() for r in rows)]
    columns = []
    for c in conditions:
        label = Condition(c).label
        columns += [
            Column(f"{label} L2 repaired"),
            Column(f"{label} resp. repaired", "rate", "higher"),
            Column(f"{label} L2 official"),
            Column(f"{label} resp. official", "rate", "higher"),
        ]
    table = Table(
        KEY,
        "Official parse beside the repaired numbers",
        "Systems parsed with a lenient parser (repairs such as trailing commas, single quotes, "
        "0-1000 rescaling): their numbers beside those of the official runner's reading of the same "
        "answers, which is the one to compare with the paper. A system whose rows carry no recorded "
        "official reading shows -- on the official side: rescore its runs with --parser official.",
        "System (parser)",
        columns,
        show_ci=False,
    )
    for system, rows in by_system.items():
        parsers = sorted({r.parser for r in rows if r.parser})
        repaired = breakdown([scored_row(r, scorer_of[system]) for r in rows])["per_condition"]
        unread = any(r.official_reading is None and r.parse is not None and r.parser not in OFFICIAL_PARSERS for r in rows)
        # lenient rows without a reading (format 0): the official side is unknown, not zero
        official = {} if unread else breakdown([scored_row(officially_read(r), scorer_of[system]) for r in rows])["per_condition"]
        cells = []
        for c in conditions:
            mine, theirs = repaired.get(c, {}), official.get(c, {})
            cells += [Cell(mine.get("mean_l2")), Cell(mine.get("response_rate")), Cell(theirs.get("mean_l2")), Cell(theirs.get("response_rate"))]
        note = "; no official reading recorded: rescore with --parser official" if unread else ""
        table.rows.append(Row(f"{system} ({', '.join(parsers)}{note})", cells))
    # bold marks the best model of a column (tables.best_rows): say so only when it happens
    table.caption += " The best model per column is in bold." if len(table.rows) >= 2 else " Nothing is bolded (bold marks the best of two or more models)."
    return table
