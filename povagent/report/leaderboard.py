"""The leaderboard: systems x sets, each cell the set's own number with its CI, and the same
answers read by every other rule one click away.

A row is an entrant (a system's name without its set: :attr:`RunInfo.entrant`), a column a set
the runs were asked (:attr:`RunInfo.benchmark`); runs of different sets are never one system
(:func:`~povagent.report.systems.assign_systems`), so a cell holds one set's questions only. The
number in a cell is the set's own: the headline metric (``Scorer.headline``, else its first
declared metric) of the run's choice scorer, as the report estimates it for every table
(:func:`~povagent.report.declared_metrics.declared_metric_estimates`). The harnesses read the
same replies differently (issue 45), so a second table gives, per system and set, the accuracy
under each registered rule that reads a choice answer (the parsers declaring the ``choice``
answer type), each reply read again from its stored text against the question's options; the
leaderboard's caption links to it.

Reads observations, the runs' estimates and the opened sets; writes nothing and never changes a
run's stored number (the readings table is a reading beside it, named as such).
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from typing import Any, Sequence

from povagent.errors import PluginError
from povagent.plugins import get_plugin_host
from povagent.report.analysis import Analysis
from povagent.report.baseline_systems import is_baseline_system
from povagent.report.collect import Collection, Observation
from povagent.report.run_sets import RunSets
from povagent.report.tables import Cell, Column, Row, Table
from povagent.scoring.bootstrap import DEFAULT_BOOT, bootstrap_mean_ci

LEADERBOARD = "leaderboard"
READINGS = "leaderboard_readings"


@dataclass(frozen=True)
class Entry:
    """One cell's system: its entrant, the set it was asked and the scorer giving its number."""

    entrant: str
    benchmark: str
    system: str
    scorer: str
    metric: str
    #: The rule that read the run's replies (its parser).
    parser: str = ""


def leaderboard_tables(
    collection: Collection, analysis: Analysis, choice_scorers: Sequence[str], dataset: Any, n_boot: int = DEFAULT_BOOT, seed: int = 0
) -> list[Table]:
    """The leaderboard and its readings table (none without a system scored by one of
    ``choice_scorers``, the scorers writing a choice scorer's fields)."""
    entries = _entries(collection, analysis, choice_scorers)
    if not entries:
        return []
    readings = _readings_table(entries, analysis.observations, dataset, n_boot, seed)
    return [_leaderboard_table(entries, analysis, collection, readings is not None)] + ([readings] if readings is not None else [])


def _entries(collection: Collection, analysis: Analysis, choice_scorers: Sequence[str]) -> list[Entry]:
    host = get_plugin_host()
    out: list[Entry] = []
    seen: set[str] = set()
    for run in collection.runs:
        if run.system in seen:
            continue
        scorer = _set_scorer(run.system, choice_scorers, analysis, host)
        if scorer is None:
            continue
        seen.add(run.system)
        out.append(
            Entry(
                run.entrant or run.system, run.benchmark or "(set not named)", run.system, scorer, _headline(scorer, analysis, host), run.axes.get("parser", "")
            )
        )
    return out


def _set_scorer(system: str, choice_scorers: Sequence[str], analysis: Analysis, host: Any) -> str | None:
    """The choice scorer giving ``system``'s number: one declaring a headline (the set's own
    scorer) before a generic one, in the order the report met them."""
    scored = [s for s in choice_scorers if system in analysis.declared_estimates.get(s, {})]
    own = [s for s in scored if _declared_headline(s, host) is not None]
    return next(iter(own or scored), None)


def _declared_headline(scorer: str, host: Any) -> str | None:
    try:
        return getattr(host.entry("scorer", scorer).factory, "headline", None)
    except PluginError:  # a scorer from a plugin this report did not load: its first metric
        return None


def _headline(scorer: str, analysis: Analysis, host: Any) -> str:
    declared = analysis.declared.get(scorer, {})
    named = _declared_headline(scorer, host)
    return named if named in declared else next(iter(declared), "")


def _leaderboard_table(entries: list[Entry], analysis: Analysis, collection: Collection, linked: bool) -> Table:
    entrants = list(dict.fromkeys(e.entrant for e in entries))
    benchmarks = list(dict.fromkeys(e.benchmark for e in entries))
    cell_of = {(e.entrant, e.benchmark): e for e in entries}
    rows = []
    for entrant in entrants:
        cells = []
        for benchmark in benchmarks:
            e = cell_of.get((entrant, benchmark))
            est = analysis.declared_estimates[e.scorer][e.system]["overall"].get(e.metric) if e is not None else None
            cells.append(Cell(est.value, est.lo, est.hi) if est is not None else Cell(None))
        system = next(e.system for e in entries if e.entrant == entrant)
        rows.append(Row(entrant, cells, reference=is_baseline_system(collection.system_axes(system), entrant)))
    numbers: dict[tuple[str, str, str], dict[str, None]] = {}
    for e in entries:
        numbers.setdefault((e.benchmark, e.scorer, e.metric), {})[e.parser or "unknown"] = None
    said = "; ".join(
        f"{b}: {_metric_label(analysis, s, m)} ({s}), read by {', '.join(f'`{p}`' for p in parsers)}" for (b, s, m), parsers in sorted(numbers.items())
    )
    caption = (
        f"Each set's own number with its 95% bootstrap CI over questions: {said}. A row is one system, a column one set; "
        "runs of different sets are never pooled, and an empty cell is a set the system was not asked. "
        + (
            "The same replies read by every rule that reads a choice answer: 'the harness readings', folded "
            "under this table on the report's page and a table of its own in the exports."
            if linked
            else ""
        )
    )
    return Table(
        key=LEADERBOARD,
        title="Leaderboard: systems x sets",
        caption=caption,
        row_header="System",
        columns=[Column(b, "rate", "higher") for b in benchmarks],
        rows=rows,
    )


def _metric_label(analysis: Analysis, scorer: str, metric: str) -> str:
    declared = analysis.declared.get(scorer, {}).get(metric)
    return declared.label if declared is not None else metric


def choice_readers(host: Any = None) -> list[str]:
    """The registered parsers that read a choice answer (``answer_types`` holds ``choice``)."""
    host = get_plugin_host() if host is None else host
    return [n for n in host.names("parser") if "choice" in getattr(host.entry("parser", n).factory, "answer_types", ())]


def _readings_table(entries: list[Entry], observations: Sequence[Observation], dataset: Any, n_boot: int, seed: int) -> Table | None:
    """Per system and set, its accuracy under each choice-reading rule (``None``: the sets
    cannot be opened, so the options to read against are unknown)."""
    if dataset is None:
        return None
    from povagent.answers.spec import AnswerSpec, choice_answer_schema

    host = get_plugin_host()
    readers = choice_readers(host)
    parsers = {name: host.parser(name, {}) for name in readers}
    wanted = {e.system: e for e in entries}
    by_system: dict[str, list[Observation]] = defaultdict(list)
    for o in observations:
        if o.system in wanted:
            by_system[o.system].append(o)
    specs: dict[tuple[str, str], Any] = {}
    rows = []
    for system, entry in wanted.items():
        hits: dict[str, dict[str, list[float]]] = {name: defaultdict(list) for name in readers}
        for o in by_system.get(system, []):
            asked = dataset.for_run(o.run_name) if isinstance(dataset, RunSets) else dataset
            key = (o.run_name, o.instance_id)
            if key not in specs:
                question = getattr(asked.instance(o.instance_id), "question", None)
                specs[key] = None if question is None else (question.gold, AnswerSpec(
                    schema=choice_answer_schema(question.labels), width=512, height=512, asks_frame=False, choices=question.options))
            known = specs[key]
            if known is None:
                continue
            gold, spec = known
            for name, parser in parsers.items():
                read = parser.parse(o.raw or "", spec)
                hits[name][o.instance_id].append(1.0 if read.choice is not None and read.choice == gold else 0.0)
        cells = [Cell(len(hits[readers[0]]) if readers else 0)]
        for name in readers:
            e = bootstrap_mean_ci([sum(v) / len(v) for v in hits[name].values()], n_boot=n_boot, seed=seed)
            cells.append(Cell(e.value, e.lo, e.hi))
        if cells[0].value:
            rows.append(Row(f"{entry.entrant} · {entry.benchmark}", cells))
    if not rows:
        return None
    return Table(
        key=READINGS,
        title="Leaderboard: the harness readings",
        caption=(
            "Each system's replies on each set read again by every registered rule that reads a choice answer "
            "(the harnesses' and the sets' own), against the question's options: correct / all questions, a reply "
            "a rule reads no option in counting as wrong, 95% bootstrap CI over questions. A reading beside the "
            "leaderboard, not the runs' stored numbers; a column per rule: " + "; ".join(f"`{n}` ({_description(host, n)})" for n in readers) + "."
        ),
        row_header="System · set",
        columns=[Column("Questions", "count", None)] + [Column(n, "rate", None) for n in readers],
        rows=rows,
        folded_under=LEADERBOARD,
    )


def _description(host: Any, parser: str) -> str:
    return host.entry("parser", parser).description or parser


__all__ = ["LEADERBOARD", "READINGS", "choice_readers", "leaderboard_tables"]
