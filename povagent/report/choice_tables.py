"""The report's tables of multiple-choice runs: accuracy per category with CIs, paired
differences between systems on the same questions, and a confusion of chosen vs gold labels.

A choice run's rows carry a choice scorer's fields (``answered, correct, chosen, gold,
category``: :mod:`povagent_plugins.scorers.choice_scorer` and the scorers built on it); a row has no
pixels, so these tables stand in for the point tables. Harnesses read the same answer
differently (issue 45), so every table names the rule that read its answers: the rows' parser,
with its registered description. Accuracy counts every scored row (no option read = wrong).
An accuracy is the mean over questions of each question's mean over runs, its 95% CI a
bootstrap over questions (:func:`~povagent.scoring.bootstrap.bootstrap_mean_ci`).

Reads the runs' rows as stored (never rescored) and, for a question no row scored, the set the
runs name (:mod:`povagent.report.choice_gold`); writes nothing.
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

import numpy as np

from povagent.errors import PluginError
from povagent.plugins import get_plugin_host
from povagent.report.baseline_systems import is_baseline_system
from povagent.report.choice_fields import CHOICE_FIELDS
from povagent.report.choice_gold import SetQuestions
from povagent.report.collect import Collection, RunInfo
from povagent.report.statistics import sign_test_p
from povagent.report.tables import Cell, Column, Row, Table
from povagent.results.rows import ResultRow, StoredRows
from povagent.scoring.bootstrap import DEFAULT_BOOT, bootstrap_mean_ci

#: The confusion column of answers naming no option.
NO_OPTION = "no option"
#: The gold label of a question no row of which was scored (every system named no option) and
#: whose set cannot be opened.
UNKNOWN = "?"
#: The accuracy column over every category.
ALL = "All"


@dataclass(frozen=True, slots=True)
class ChoiceAnswer:
    """One row of a choice run, as these tables read it (slotted: one per row)."""

    system: str
    instance_id: str
    correct: bool
    chosen: str | None
    gold: str
    category: str
    parser: str
    #: The set the row's run was asked (:attr:`~povagent.report.collect.RunInfo.benchmark`).
    benchmark: str = ""


def choice_answers(collection: Collection, sets: SetQuestions | None = None) -> dict[str, list[ChoiceAnswer]]:
    """Per choice scorer (in the order first met), the rows of the runs it scored, run by run.

    A row the scorer did not score (no option read, a failed request: the runner scores only
    answers) counts as an answer naming no option, as the scorer's accuracy counts it; its gold
    label and category are the question's as another row of it records them, or, when no row of
    the question was scored, as the set the run names holds them (``sets``; :data:`UNKNOWN`
    when that set cannot be opened)."""
    sets = SetQuestions() if sets is None else sets
    carried = [_choice_scorers(run.rows) for run in collection.runs]
    scorers = sorted(set().union(*carried), key=lambda name: next(i for i, c in enumerate(carried) if name in c))
    questions: dict[tuple[str, str], tuple[str, str]] = {}
    unscored: list[tuple[str, int, RunInfo]] = []  # (scorer, position in its answers, run) of rows it did not score
    out: dict[str, list[ChoiceAnswer]] = {scorer: [] for scorer in scorers}
    for run, its_own in zip(collection.runs, carried):
        named = {_scorer_name(s) for s in run.config.get("scorers") or []}
        mine = [s for s in scorers if s in named or s in its_own]
        if not mine:
            continue  # no choice scorer of this run: its rows are not read
        benchmark = run.benchmark
        for row in run.rows:
            for scorer in mine:
                f = row.scores.get(scorer) or {}
                if f.keys() >= CHOICE_FIELDS:
                    questions[(scorer, row.instance_id)] = (str(f["gold"]), str(f["category"] or ""))
                    chosen = None if f["chosen"] is None else str(f["chosen"])
                    out[scorer].append(
                        ChoiceAnswer(run.system, row.instance_id, f["correct"] is True, chosen, str(f["gold"]), str(f["category"] or ""), row.parser, benchmark)
                    )
                else:
                    unscored.append((scorer, len(out[scorer]), run))
                    out[scorer].append(ChoiceAnswer(run.system, row.instance_id, False, None, "", "", row.parser, benchmark))
    for scorer, position, run in unscored:
        answer = out[scorer][position]
        question = questions.get((scorer, answer.instance_id)) or sets.question(run, answer.instance_id) or (UNKNOWN, "")
        out[scorer][position] = dataclasses.replace(answer, gold=question[0], category=question[1])
    return out


def _choice_scorers(rows: Sequence[ResultRow]) -> set[str]:
    """The scorers that wrote a choice verdict (:data:`CHOICE_FIELDS`) into some row of ``rows``."""
    if isinstance(rows, StoredRows):  # known from its one reading of the file
        return {scorer for scorer, shapes in rows.carried_scores.items() if any(f >= CHOICE_FIELDS for f in shapes)}
    return {scorer for row in rows for scorer, f in row.scores.items() if f.keys() >= CHOICE_FIELDS}


def _scorer_name(spec: object) -> str:
    return str(spec.get("name", "")) if isinstance(spec, dict) else str(spec)


def choice_tables(
    collection: Collection, n_boot: int = DEFAULT_BOOT, seed: int = 0, sets: SetQuestions | None = None,
    read: dict[str, list[ChoiceAnswer]] | None = None,
) -> list[Table]:
    """Each choice scorer's accuracy table, paired differences (with two systems or more) and a
    confusion table per system (none for a report without choice rows), per set the runs were
    asked. ``sets``: the sets the report opened already (each set the runs name is opened once,
    for every scorer); ``read``: :func:`choice_answers`, when the report read them already."""
    tables: list[Table] = []
    sets = SetQuestions() if sets is None else sets
    for scorer, all_answers in (choice_answers(collection, sets) if read is None else read).items():
        by_set: dict[str, list[ChoiceAnswer]] = defaultdict(list)
        for a in all_answers:
            by_set[a.benchmark].append(a)
        baselines = {s for s in collection.systems if is_baseline_system(collection.system_axes(s), s)}
        for benchmark, answers in by_set.items():  # a set's questions are never pooled with another's
            # one set keeps the tables' plain names; several are told apart by the set's
            key = scorer if len(by_set) == 1 else f"{scorer}_{_slug(benchmark)}"
            named = scorer if len(by_set) == 1 else f"{scorer}, {benchmark}"
            systems = list(dict.fromkeys(a.system for a in answers))
            unknown = sets.why_unknown(len({a.instance_id for a in answers if a.gold == UNKNOWN}))
            read_by = rules_note(answers, systems) + (f" {unknown}" if unknown else "")
            tables.append(_accuracy_table(key, named, answers, systems, read_by, n_boot, seed, baselines))
            if len(systems) > 1:
                tables.append(_paired_table(key, named, answers, systems, read_by, n_boot, seed))
            tables += [_confusion_table(key, named, i, system, [a for a in answers if a.system == system], read_by) for i, system in enumerate(systems)]
    return tables


def _slug(text: str) -> str:
    """A set's name as a table key's part (``release · relation`` -> ``release_relation``)."""
    return "_".join("".join(c if c.isalnum() else " " for c in text).split()) or "set"


def rule_name(parser: str) -> str:
    """A parser named with its registered description (the rule and the commit it follows)."""
    try:
        description = get_plugin_host().entry("parser", parser).description
    except PluginError:  # a run's parser from a plugin this report did not load: its name alone
        description = ""
    return f"`{parser}` ({description})" if description else f"`{parser}`"


def rules_note(answers: list[ChoiceAnswer], systems: list[str]) -> str:
    """Which rule read the answers: one sentence naming each parser (and its systems when they differ)."""
    by_parser: dict[str, list[str]] = defaultdict(list)
    for system in systems:
        for parser in dict.fromkeys(a.parser for a in answers if a.system == system):
            by_parser[parser].append(system)
    if len(by_parser) == 1:
        return f"Read by {rule_name(next(iter(by_parser)) or 'unknown')}."
    parts = [f"{rule_name(p or 'unknown')} for {', '.join(s)}" for p, s in by_parser.items()]
    return "Read by " + "; by ".join(parts) + " (different rules: the systems' numbers are not read alike)."


def per_question(answers: list[ChoiceAnswer]) -> dict[str, float]:
    """Each question's accuracy over its runs, questions in id order (the order a bootstrap over
    questions draws from: not the order the rows were written in)."""
    hits: dict[str, list[float]] = defaultdict(list)
    for a in answers:
        hits[a.instance_id].append(1.0 if a.correct else 0.0)
    return {k: sum(v) / len(v) for k, v in sorted(hits.items())}


def _accuracy_table(
    scorer: str, named: str, answers: list[ChoiceAnswer], systems: list[str], read_by: str, n_boot: int, seed: int, baselines: set[str]
) -> Table:
    categories = sorted({a.category for a in answers})
    columns = [c or "(none)" for c in categories] + [ALL] if len(categories) > 1 else [ALL]
    rows = []
    for system in systems:
        mine = [a for a in answers if a.system == system]
        groups = [[a for a in mine if a.category == c] for c in categories] + [mine] if len(categories) > 1 else [mine]
        cells = []
        for group in groups:
            e = bootstrap_mean_ci(list(per_question(group).values()), n_boot=n_boot, seed=seed)
            cells.append(Cell(e.value, e.lo, e.hi))
        rows.append(Row(system, cells, reference=system in baselines))  # a baseline is never bolded as best
    return Table(
        key=f"choice_accuracy_{scorer}",
        title=f"Multiple-choice accuracy per category ({named})",
        caption=f"Correct / all questions per category (no option read = wrong), 95% bootstrap CI over questions. {read_by}",
        row_header="System",
        columns=[Column(c, "rate", "higher") for c in columns],
        rows=rows,
    )


def _paired_table(scorer: str, named: str, answers: list[ChoiceAnswer], systems: list[str], read_by: str, n_boot: int, seed: int) -> Table:
    acc = {s: per_question([a for a in answers if a.system == s]) for s in systems}
    rows = []
    for a, b in combinations(systems, 2):
        shared = sorted(set(acc[a]) & set(acc[b]))
        d = np.array([acc[b][k] - acc[a][k] for k in shared], dtype=float)
        diff = bootstrap_mean_ci(d, n_boot=n_boot, seed=seed)
        va = float(np.mean([acc[a][k] for k in shared])) if shared else None
        vb = float(np.mean([acc[b][k] for k in shared])) if shared else None
        p = sign_test_p(int((d > 1e-12).sum()), int((d < -1e-12).sum()))
        rows.append(Row(f"{b} vs {a}", [Cell(len(shared)), Cell(va), Cell(vb), Cell(diff.value, diff.lo, diff.hi), Cell(p)]))
    return Table(
        key=f"choice_paired_{scorer}",
        title=f"Paired accuracy differences ({named})",
        caption=(
            "B - A: system B's accuracy minus system A's on the questions both were asked (accuracy averaged over runs per "
            "question; B - A > 0 means B is better), 95% paired bootstrap CI over questions; exact sign test over questions "
            f"that differ. {read_by}"
        ),
        row_header="B vs A",
        columns=[
            Column("Questions", "count", None),
            Column("Accuracy A", "rate", None),
            Column("Accuracy B", "rate", None),
            Column("B - A", "signed", None),
            Column("Sign test p", "p", None),
        ],
        rows=rows,
    )


def _confusion_table(scorer: str, named: str, index: int, system: str, answers: list[ChoiceAnswer], read_by: str) -> Table:
    labels = sorted({a.gold for a in answers} | {a.chosen for a in answers if a.chosen is not None})
    counts: dict[tuple[str, str], int] = defaultdict(int)
    for a in answers:
        counts[(a.gold, a.chosen if a.chosen is not None else NO_OPTION)] += 1
    golds = sorted({a.gold for a in answers})
    return Table(
        key=f"choice_confusion_{scorer}_{index + 1}",
        title=f"Chosen vs gold labels: {system} ({named})",
        caption=f"Rows: the gold label; columns: the label chosen (every run's row counts once). {read_by}",
        row_header="Gold",
        columns=[Column(label, "count", None) for label in labels] + [Column(NO_OPTION, "count", None)],
        rows=[Row(g, [Cell(counts[(g, c)]) for c in labels + [NO_OPTION]]) for g in golds],
        show_ci=False,
    )
