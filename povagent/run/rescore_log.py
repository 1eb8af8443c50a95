"""A second opinion on a run another harness made: every logged reply scored by every rule of its set.

``povagent rescore-log FILE --harness H --set S`` reads the log (:mod:`povagent.results.harness_log_files`),
and scores each reply with the set's official rule and each harness rule povagent has for the set
(:func:`povagent.scoring.log_rules.set_rules`): no model, no media, nothing but the file named. A
reply is parsed and scored by the score step ``run`` and ``rescore`` use
(:class:`~povagent.run.score_step.AnswerScoring`): a question with options as a choice question,
one whose log gives a gold number and no options (VSI-Bench's counts and distances) as a numerical
question, which a set whose answers are only choices leaves out, named. Each rule's numbers are
its scorer's declared metrics, overall and per category, each with its 95% bootstrap CI,
estimated as a run's summary estimates them (:func:`~povagent.scoring.metric_columns.metric_slices`). The rule's headline is
its scorer's ``headline`` metric (else its first). A reply a rule's scorer cannot score (its
fields say ``unscorable``, as a VSI-Bench gold of 0 makes the set's own scorer say, or the scorer
failed) is left out of that rule's figures and named in its ``unscorable`` list, never dropped
silently. What it writes is :class:`RescoredLog`.

This module must not print (the CLI does) nor write files.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.numeric_question import NumericQuestion, number_answer_schema
from povagent.answers.spec import AnswerSpec
from povagent.dataset.problems import Problem
from povagent.results.harness_log_files import read_harness_log
from povagent.results.harness_logs import HarnessLog, LoggedReply
from povagent.run.score_step import AnswerScoring
from povagent.scoring.bootstrap import DEFAULT_BOOT, Estimate
from povagent.scoring.log_rules import LogRule, set_rules
from povagent.scoring.metric_columns import MetricColumns, metric_slices
from povagent.scoring.metrics import valued_row

#: Disagreements kept in the JSON at most (the count is always whole).
MAX_DISAGREEMENTS = 10_000
#: How much of a reply a disagreement quotes.
REPLY_EXCERPT = 200
#: What a rule is asked to read in the reply to a numerical question.
_NUMBER_SPEC = AnswerSpec(schema=number_answer_schema(), asks_frame=False)


class Figure(BaseModel):
    """A metric's value with its 95% bootstrap CI over questions and the questions counted."""

    model_config = ConfigDict(frozen=True)

    value: float | None
    ci_lo: float | None = None
    ci_hi: float | None = None
    n: int = 0


class RuleResult(BaseModel):
    """One rule's numbers on the log's replies."""

    rule: str = Field(description="The rule: a registered parser (with +scorer where two rules share it).")
    source: str = Field(description="Where the rule comes from, owner/repo@commit.")
    harness: str = Field(description="Whose rule it is: lmms-eval, VLMEvalKit, or the set's own code.")
    official: bool = Field(description="The set's official rule.")
    parser: str
    scorer: str
    metric: str = Field(description="The scorer's headline metric: what overall and per_category give.")
    reads: str = Field(description="The log field the rule read, and the filter it applied to it first.")
    overall: float | None
    overall_ci: tuple[float, float] | None = None
    per_category: dict[str, float | None] = Field(default_factory=dict)
    per_category_ci: dict[str, tuple[float, float] | None] = Field(default_factory=dict)
    answered: int = Field(description="Replies the rule read an answer in: an option label, or a number for a numerical question.")
    metrics: dict[str, Figure] = Field(default_factory=dict, description="Every metric the scorer declares, overall.")
    unscorable: list[str] = Field(
        default_factory=list,
        description=(
            "The replies the rule's scorer could not score, each named by row and field with why (a numerical gold of 0, "
            "a scorer failure): left out of the rule's figures."
        ),
    )


class Disagreement(BaseModel):
    """A question the rules read differently: each rule's label (``null``: none; a numerical
    question's number, as text) and hit (a numerical question's: every MRA threshold met)."""

    item: str
    where: str
    #: The reply's first :data:`REPLY_EXCERPT` characters.
    reply: str
    gold: str
    labels: dict[str, str | None]
    correct: dict[str, bool]


class RescoredLog(BaseModel):
    """``povagent rescore-log --json``: the log's replies scored by each rule of its set."""

    set: str
    harness: str
    file: str
    items: int = Field(description="Records scored.")
    numerical: int = Field(0, description="Of them, the questions answered with a number (VSI-Bench's counts and distances), scored by their numerical metric.")
    bad_records: int = Field(description="Records left out, each named in problems.")
    problems: list[str] = Field(default_factory=list)
    stripped: int = Field(description="Replies the harness's own filter changed (lmms-eval: resps differs from filtered_resps).")
    notes: list[str] = Field(default_factory=list, description="What a reader of the numbers must know about the log as a whole.")
    rules: list[RuleResult]
    disagreements_total: int = 0
    disagreements: list[Disagreement] = Field(default_factory=list)


@dataclass(frozen=True, slots=True)
class _LoggedRow:
    """A reply scored by one rule, as the metric breakdown reads a row."""

    status: str
    scores: dict[str, dict[str, Any]]
    category: str | None
    main_category: str | None
    pair_id: str
    condition: None = None
    direction: None = None
    run: int = 0


def _instance(set_name: str, reply: LoggedReply) -> Any:
    """The reply's question as an instance with no image (only the scorer reads it): a choice
    question, or a numerical one where the log gives a gold number."""
    from dataclasses import replace

    from povagent.dataset.choice_sets.external import Item, choice_instance

    question = ChoiceQuestion(
        "",
        reply.options or (("A", ""),),
        reply.gold if reply.gold_number is None else "A",
        category=reply.category,
        group=reply.question_id,
        main_category=reply.main_category,
    )
    instance = choice_instance(set_name, Item(reply.item, question, ()), ())
    if reply.gold_number is None:
        return instance
    return replace(instance, question=None, numeric=NumericQuestion("", reply.gold_number, category=reply.category))


def _spec(reply: LoggedReply, specs: dict[tuple[tuple[str, str], ...], AnswerSpec]) -> AnswerSpec:
    """What the rule is asked to read: the question's options, or a number (one spec per option set)."""
    if reply.gold_number is not None:
        return _NUMBER_SPEC
    spec = specs.get(reply.options)
    if spec is None:
        spec = specs[reply.options] = AnswerSpec(schema={}, asks_frame=False, choices=reply.options)
    return spec


def _label(parse: Any) -> str | None:
    """What a rule read, as a disagreement shows it: the label, the number, or ``None``."""
    if not parse.answered:
        return None
    return parse.choice if parse.choice is not None else (f"{parse.number:g}" if parse.number is not None else None)


def _answer_types(host: Any, set_name: str) -> str:
    from povagent.dataset.formats import registered_formats

    return registered_formats(host)[set_name].answer_type


def _numbers_left_out(log: HarnessLog, set_name: str) -> None:
    """Drop from ``log`` the numerical questions of a set whose answers are choices, each named."""
    kept = []
    for reply in log.replies:
        if reply.gold_number is None:
            kept.append(reply)
        else:
            message = f"the {log.gold_field} {reply.gold!r:.60} is a number, and {set_name}'s answers are option labels; record left out"
            log.problems.append(Problem(str(log.file), f"{reply.where}.{log.gold_field}", message))
    log.replies[:] = kept


def _reads(rule: LogRule, log: HarnessLog) -> str:
    """Which field of the log the rule read, and what it did to it first."""
    shown = log.reply_field or "the reply"
    if rule.harness_filter:
        same = f" (lmms-eval's own {log.filtered_field})" if rule.harness == "lmms-eval" and log.filtered_field else ""
        return f"{shown}, then {rule.harness_filter}{same}"
    return f"{shown} as written"


def _figure(estimate: Estimate) -> Figure:
    return Figure(value=estimate.value, ci_lo=estimate.lo, ci_hi=estimate.hi, n=estimate.n)


def _ci(estimate: Estimate | None) -> tuple[float, float] | None:
    return (estimate.lo, estimate.hi) if estimate is not None and estimate.lo is not None and estimate.hi is not None else None


def rescore_log(file: str | Path, harness: str, set_name: str, *, host: Any = None, n_boot: int = DEFAULT_BOOT, seed: int = 0) -> RescoredLog:
    """The log ``file`` (written by ``harness``) scored by every rule of ``set_name`` (module docstring)."""
    from povagent.plugins import get_plugin_host

    host = host or get_plugin_host()
    rules = set_rules(host, set_name)  # an unknown set is refused before the file is read
    log = read_harness_log(file, harness)
    if "number" not in _answer_types(host, set_name):
        _numbers_left_out(log, set_name)
    instances = [_instance(set_name, r) for r in log.replies]
    specs: dict[tuple[tuple[str, str], ...], AnswerSpec] = {}
    labels: dict[str, list[str | None]] = {}
    hits: dict[str, list[bool]] = {}
    results = []
    for rule in rules:
        scorer = host.scorer(rule.scorer, {})
        scoring = AnswerScoring(host.parser(rule.parser, {}), {rule.scorer: scorer}, None)
        declared = {rule.scorer: tuple(scorer.metrics)}
        columns = MetricColumns(declared)
        labels[rule.name], hits[rule.name] = [], []
        unscorable: list[str] = []
        for reply, instance in zip(log.replies, instances):
            scored = scoring.score_answer(instance, _spec(reply, specs), reply.reply)
            fields = scored.scores.get(rule.scorer, {})
            if why := _unscorable(fields):
                unscorable.append(f"{log.file}: {reply.where}.{log.gold_field}: {why}; left out of {rule.name}'s figures")
            labels[rule.name].append(_label(scored.parse))
            # a numerical question is a hit when every MRA threshold is met (its score is 1)
            hits[rule.name].append(fields.get("correct") is True or (reply.gold_number is not None and fields.get("score") == 1.0))
            row = _LoggedRow(str(scored.status), scored.scores, reply.category or None, reply.main_category or None, reply.question_id)
            valued = valued_row(row, declared)
            columns.append([valued.values[rule.scorer][m.name] for m in declared[rule.scorer]], None, None, valued.category, valued.groups)
        results.append(_result(rule, log, scorer, columns, n_boot, seed, sum(label is not None for label in labels[rule.name]), unscorable))
    disagreements = [
        Disagreement(
            item=r.item,
            where=r.where,
            reply=r.reply[:REPLY_EXCERPT],
            gold=r.gold,
            labels={n: labels[n][k] for n in labels},
            correct={n: hits[n][k] for n in hits},
        )
        for k, r in enumerate(log.replies)
        if len({labels[n][k] for n in labels}) > 1
    ]
    return RescoredLog(
        set=set_name,
        harness=harness,
        file=str(file),
        items=len(log.replies),
        numerical=sum(r.gold_number is not None for r in log.replies),
        bad_records=len(log.problems),
        problems=[str(p) for p in log.problems],
        stripped=log.stripped,
        notes=log.notes,
        rules=results,
        disagreements_total=len(disagreements),
        disagreements=disagreements[:MAX_DISAGREEMENTS],
    )


def _unscorable(fields: Any) -> str:
    """Why a scorer's fields leave the reply unscored (``""``: they do not): the scorer said
    ``unscorable`` (with its ``unscorable_reason``), or it failed (``error``)."""
    if not isinstance(fields, dict):
        return ""
    if fields.get("unscorable") is True:
        return str(fields.get("unscorable_reason") or "the scorer cannot score it")
    return f"the scorer failed ({fields['error']})" if fields.get("error") else ""


def _result(rule: LogRule, log: HarnessLog, scorer: Any, columns: MetricColumns, n_boot: int, seed: int, answered: int, unscorable: list[str]) -> RuleResult:
    """One rule's :class:`RuleResult` from its rows' metric columns."""
    metrics = tuple(scorer.metrics)
    headline = getattr(scorer, "headline", None) or metrics[0].name
    by_slice: dict[str, Any] = metric_slices(columns, rule.scorer, n_boot, seed) if len(columns) else {"overall": {m.name: Estimate(None) for m in metrics}}
    overall = by_slice["overall"]
    per_category = by_slice.get("per_category", {})
    return RuleResult(
        rule=rule.name,
        source=rule.source,
        harness=rule.harness,
        official=rule.official,
        parser=rule.parser,
        scorer=rule.scorer,
        metric=headline,
        reads=_reads(rule, log),
        overall=overall[headline].value,
        overall_ci=_ci(overall[headline]),
        per_category={c: cell[headline].value for c, cell in per_category.items()},
        per_category_ci={c: _ci(cell[headline]) for c, cell in per_category.items()},
        answered=answered,
        metrics={name: _figure(e) for name, e in overall.items()},
        unscorable=unscorable,
    )
