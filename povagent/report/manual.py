"""Manual assessment in the report: success judged by hand, per system and condition, and how
far two judges agree.

The judgements come from ``povagent annotate``'s judge mode (:mod:`povagent.results.judgements`):
the files in a ``judgements/`` folder inside the report's source folder or beside it. A rate is
success / (success + failure) over every judgement (judges pooled), with a 95% Wilson interval;
"can't tell" counts in neither and is reported beside. Where two judges judged the same
predictions, their agreement and Cohen's kappa over the three verdicts are shown. Only the
judgements of the report's own runs count: a judgement names its prediction by the judged run's
identity, row key and prediction (:func:`~povagent.results.judgements.judged_item`), and a
judgement of any other run (a neighbouring sweep's, a cell of the same name elsewhere) is left out.
"""

from __future__ import annotations

import math
from collections import Counter, defaultdict
from itertools import combinations
from pathlib import Path
from typing import Any, Sequence

from povagent.report.tables import Cell, Column, Row, Table
from povagent.results.judgements import JUDGEMENTS_FOLDER, VERDICTS, Judgement, judged_item, read_judgements, run_identity

#: z of a two-sided 95% interval.
Z95 = 1.959963984540054


def judgement_files(source: Path) -> list[Path]:
    """The judges' files a report of ``source`` reads: ``judgements/*.jsonl`` in it or beside it."""
    found: dict[Path, None] = {}
    for folder in (source / JUDGEMENTS_FOLDER, source.parent / JUDGEMENTS_FOLDER):
        if folder.is_dir():
            for f in sorted(folder.glob("*.jsonl")):
                found.setdefault(f.resolve(), None)
    return list(found)


def wilson(successes: int, n: int) -> Cell:
    """The rate and its 95% Wilson score interval (no value for ``n == 0``)."""
    if n == 0:
        return Cell(None)
    p = successes / n
    centre = (p + Z95**2 / (2 * n)) / (1 + Z95**2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + Z95**2 / (4 * n * n)) / (1 + Z95**2 / n)
    return Cell(p, max(0.0, centre - half), min(1.0, centre + half))


def cohen_kappa(first: list[str], second: list[str]) -> float | None:
    """Cohen's kappa of two judges' verdicts on the same items, in the same order (``None`` when
    chance agreement is certain: both gave one and the same verdict throughout)."""
    n = len(first)
    if n == 0:
        return None
    observed = sum(a == b for a, b in zip(first, second)) / n
    c1, c2 = Counter(first), Counter(second)
    expected = sum(c1[v] * c2[v] for v in VERDICTS) / (n * n)
    return None if expected >= 1.0 else (observed - expected) / (1.0 - expected)


def judged_items_of(runs: Sequence[Any]) -> set[str]:
    """The item names (:func:`~povagent.results.judgements.judged_item`) of every prediction
    with a point in ``runs`` (each a run's ``folder`` and its ``rows``)."""
    items: set[str] = set()
    for run in runs:
        identity = run_identity(run.folder)
        items.update(judged_item(identity, row.key, row.prediction) for row in run.rows if row.prediction.x is not None)
    return items


def manual_tables(source: Path, runs: Sequence[Any]) -> list[Table]:
    """The manual success table and, where judges overlap, the agreement table, over the
    judgements of predictions of ``runs`` (the report's runs) only; none without such judgements."""
    judgements = [j for f in judgement_files(source) for j in read_judgements(f)]
    if judgements:  # the runs' rows are read again only when someone judged something
        own = judged_items_of(runs)
        judgements = [j for j in judgements if j.item in own]
    if not judgements:
        return []
    tables = [_success_table(judgements)]
    agreement = _agreement_table(judgements)
    if agreement is not None:
        tables.append(agreement)
    return tables


def _success_table(judgements: list[Judgement]) -> Table:
    conditions = sorted({j.condition for j in judgements})
    systems = list(dict.fromkeys(j.system for j in judgements))
    tally: dict[tuple[str, str], Counter] = defaultdict(Counter)
    for j in judgements:
        tally[(j.system, j.condition)][j.verdict] += 1
        tally[(j.system, "")][j.verdict] += 1
    rows = []
    for system in systems:
        cells = [wilson(tally[(system, c)]["success"], tally[(system, c)]["success"] + tally[(system, c)]["failure"]) for c in conditions + [""]]
        overall = tally[(system, "")]
        cells += [Cell(float(overall["success"] + overall["failure"])), Cell(float(overall["cant_tell"]))]
        rows.append(Row(system, cells))
    columns = [Column(c, "rate", "higher") for c in conditions] + [
        Column("All", "rate", "higher"),
        Column("Judged", "count", None),
        Column("Can't tell", "count", None),
    ]
    judges = sorted({j.judge for j in judgements})
    return Table(
        "manual_success", "Manual assessment: success judged by hand",
        f"Success / (success + failure) per system and condition with 95% Wilson intervals, judged blind by "
        f"{', '.join(judges)} (judges pooled); 'can't tell' counts in neither.",
        "System", columns, rows,
    )


def _agreement_table(judgements: list[Judgement]) -> Table | None:
    by_judge: dict[str, dict[str, str]] = defaultdict(dict)
    for j in judgements:
        by_judge[j.judge][j.item] = j.verdict  # a judge's last word on an item
    rows = []
    for a, b in combinations(sorted(by_judge), 2):
        shared = sorted(set(by_judge[a]) & set(by_judge[b]))
        if not shared:
            continue
        first, second = [by_judge[a][i] for i in shared], [by_judge[b][i] for i in shared]
        agree = sum(x == y for x, y in zip(first, second)) / len(shared)
        rows.append(Row(f"{a} / {b}", [Cell(float(len(shared))), Cell(agree), Cell(cohen_kappa(first, second))]))
    if not rows:
        return None
    return Table(
        "manual_agreement", "Manual assessment: agreement between judges",
        "Predictions two judges both judged: the share they gave the same verdict (success, failure, can't tell) and Cohen's kappa.",
        "Judges", [Column("Both judged", "count", None), Column("Agreement", "rate", None), Column("Cohen's kappa", "signed", None)], rows,
        show_ci=False,
    )
