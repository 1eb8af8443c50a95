"""``summary.json`` as a type: :class:`RunSummary` and the sections it is made of.

The runner (and ``rescore``, and :func:`povagent.run.summary.summarize_run`) build the summary as
JSON; this module says what that JSON is, so a reader validates it once and reads attributes,
and ``povagent schema summary`` publishes its JSON Schema. A section that only some runs have
(a lenient parser's ``official_parse``, a real-world set's ``success``, the diagnostics) is
``None`` when absent. The breakdown's cells are strict about the fields every cell has and let
the multi-run fields (``n_runs``, ``run_mean_l2``) through.

Only types: nothing here reads or writes a file.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict

from povagent.results.upgrade import SUMMARY_FORMAT
from povagent.scoring.metrics import Metric


class Cell(BaseModel):
    """One cell of a breakdown (all rows, a condition, a direction, a run): see
    :func:`povagent.scoring.breakdown.summarize`."""

    model_config = ConfigDict(extra="forbid")

    n: int
    n_total: int
    response_rate: float | None
    mean_l2: float | None
    std_l2: float | None
    pct_in_frame: float | None
    mean_l2_strict: float | None
    mean_abs_x: float | None
    mean_abs_y: float | None
    n_parse_error: int
    #: With several runs: how many runs the mean is over, and each run's mean.
    n_runs: int | None = None
    run_mean_l2: list[float | None] | None = None


class PooledBreakdown(BaseModel):
    """Overall, per condition, per direction and per condition/direction cells of rows in one
    mean: see :func:`povagent.scoring.breakdown.pooled_breakdown`."""

    model_config = ConfigDict(extra="forbid")

    overall: Cell
    per_condition: dict[str, Cell]
    per_direction: dict[str, Cell]
    per_condition_direction: dict[str, Cell]
    #: ``mean of per-run means`` (the paper's number) or ``pooled``.
    aggregation: str


class Breakdown(PooledBreakdown):
    """The breakdown of a run's rows: see :func:`povagent.scoring.breakdown.breakdown`."""

    runs: list[int]
    n_parse_error: int
    #: With several runs: every row in one mean, beside the mean of per-run means.
    pooled: PooledBreakdown | None = None
    #: With several runs: each run's overall cell, by run index.
    per_run: dict[str, Cell] | None = None


class OfficialParseBreakdown(Breakdown):
    """The paper-comparable reading beside a lenient parser's (``official_parse``)."""

    parser: str
    rows_without_reading: int


class RowCounts(BaseModel):
    """How many of the run's keys have a row, and with which status."""

    model_config = ConfigDict(extra="forbid")

    total: int
    done: int
    missing: int
    answered: int
    parse_error: int
    infra_error: int


class UsageTotals(BaseModel):
    """Tokens, cost and retries summed over the run's rows (cost ``None``: no row priced)."""

    model_config = ConfigDict(extra="forbid")

    prompt_tokens: int
    completion_tokens: int
    cost_usd: float | None
    retries: int


class PipelineNames(BaseModel):
    """What answered and how: the registered names, the model and the config hash."""

    model_config = ConfigDict(extra="forbid")

    backend: str
    model: str
    profile: str | None
    strategy: str
    parser: str
    scorers: list[str]
    config_hash: str


class SuccessCell(BaseModel):
    """A real-world set's success rate in one slice (unanswered = failure): see
    :func:`povagent.dataset.realworld_set.success_breakdown`; the answered counts when the rows say
    whether they were answered."""

    model_config = ConfigDict(extra="forbid")

    n_total: int
    n_success: int
    success_rate: float | None
    n_answered: int | None = None
    response_rate: float | None = None


class SuccessBreakdown(BaseModel):
    """A real-world set's success rates, overall and per slice."""

    model_config = ConfigDict(extra="forbid")

    overall: SuccessCell
    per_condition: dict[str, SuccessCell]
    per_direction: dict[str, SuccessCell]
    per_condition_direction: dict[str, SuccessCell]


class DiagnosedDirection(BaseModel):
    """Relation-consistent success of one direction's answered rows, beside their official mean."""

    model_config = ConfigDict(extra="forbid")

    n: int
    relation_success: float | None
    official_mean_l2: float | None


class DiagnosedCondition(BaseModel):
    """Why one condition's answers failed: see :mod:`povagent.scoring.diagnostics_breakdown`."""

    model_config = ConfigDict(extra="forbid")

    n_diagnosed: int
    #: The share of diagnosed rows per first failing step (``None``: no row diagnosed).
    failure_steps: dict[str, float | None]
    egocentric_bias: float | None
    egocentric_bias_ci: list[float] | None
    bias_n: int
    #: Why the bias is left out (condition C only).
    egocentric_bias_note: str | None = None
    relation_success: float | None
    relation_n: int
    per_direction: dict[str, DiagnosedDirection]


class Diagnostics(BaseModel):
    """``summary.json``'s ``diagnostics`` section (an addition, labelled as one)."""

    model_config = ConfigDict(extra="forbid")

    label: str
    per_condition: dict[str, DiagnosedCondition]


class SessionCounters(BaseModel):
    """What the session that wrote the summary did (:class:`povagent.run.runner.RunStats`)."""

    model_config = ConfigDict(extra="forbid")

    requests: int
    cache_hits: int
    retries: int
    rows_written: int
    prompt_tokens: int
    completion_tokens: int
    cost_usd: float
    wall_s: float
    fsyncs: int
    fsync_s: float
    #: Rows written this session, by status.
    statuses: dict[str, int]


class ImageCounters(BaseModel):
    """The image store's counters (:class:`povagent.exchange.images.ImageStoreStats`) and how
    many distinct images it held."""

    model_config = ConfigDict(extra="forbid")

    file_reads: int
    png_encodes: int
    base64_encodes: int
    rebuilds: int
    distinct: int


class MetricEstimate(BaseModel):
    """One declared metric over one slice: its value, 95% bootstrap CI and the rows it counts."""

    model_config = ConfigDict(extra="forbid")

    value: float | None
    ci_lo: float | None
    ci_hi: float | None
    n: int


class MetricDeclaration(BaseModel):
    """What a scorer declared of a metric (:class:`povagent.scoring.metrics.Metric`)."""

    model_config = ConfigDict(extra="forbid")

    label: str
    caption: str
    better: Literal["lower", "higher"]
    aggregation: Literal["mean", "rate"]
    #: The scorer's row field the value is read from, which rows count, and whether a false value is the hit.
    field: str
    over: Literal["answered", "all"]
    negate: bool
    #: The scorer's row field naming a row's group, for a rate over groups (``None``: over rows).
    group: str | None = None
    #: Question categories the overall cell leaves out (their own slices keep them).
    overall_excludes: list[str] | None = None
    #: The value a mean over every row gives a row the scorer did not score (``None``: absent).
    unscored: float | None = None
    #: The overall cell is the mean of the per-category means (categories of a group in
    #: ``merged_categories`` first averaged into one); ``None``: the mean over rows.
    category_mean: bool | None = None
    merged_categories: list[list[str]] | None = None
    #: The groups merge only when each of their categories has rows (``None``: whatever is present).
    merge_only_whole: bool | None = None
    #: A pattern a row's pair id must contain to count (``None``: every row).
    select: str | None = None

    def metric(self, name: str) -> Metric:
        """The declared metric, to compute again from rows."""
        return Metric.declared(name, self.model_dump())


class ScorerMetrics(BaseModel):
    """One scorer's declared metrics, per slice (:func:`povagent.scoring.metric_columns.metrics_breakdown`)."""

    model_config = ConfigDict(extra="forbid")

    declared: dict[str, MetricDeclaration]
    overall: dict[str, MetricEstimate]
    per_condition: dict[str, dict[str, MetricEstimate]]
    per_direction: dict[str, dict[str, MetricEstimate]]
    per_condition_direction: dict[str, dict[str, MetricEstimate]]
    #: Per question category (a multiple-choice run's; absent otherwise).
    per_category: dict[str, dict[str, MetricEstimate]] | None = None


class ScoreSummary(Breakdown):
    """What ``povagent score`` computes for one model's predictions: the breakdown, the run
    folders it averaged (a root of ``<model>_<run>`` folders), how rows were counted, and the
    scorer's declared metrics over every row (runs pooled), as a run's summary has them."""

    run_folders: list[str] | None = None
    #: ``official`` or ``povagent`` (``score --counting``).
    counting: str | None = None
    #: The declared metrics, per slice: ``{scorer: ScorerMetrics}``.
    metrics: dict[str, ScorerMetrics] | None = None


class RunSummary(Breakdown):
    """Everything ``summary.json`` holds.

    The breakdown's fields are the official metric's numbers; ``rows`` and ``usage`` cover the
    run's keys (``rescore``'s summary has ``parse_status`` and ``repaired`` instead); ``pipeline``, ``complete``, ``interrupted``, ``stopped``, ``session`` and
    ``images`` are written by the runner (a summary made from a results file alone has none).
    """

    #: The summary format it was written in (:data:`~povagent.results.upgrade.SUMMARY_FORMAT`;
    #: a summary read from a file is in the current one: :func:`~povagent.results.upgrade.upgrade_summary`).
    format_version: int = SUMMARY_FORMAT
    official_parse: OfficialParseBreakdown | None = None
    #: A real-world set's success rates (:func:`povagent.dataset.realworld_set.success_breakdown`).
    success: SuccessBreakdown | None = None
    #: Each plugin scorer's true/false and number fields: ``{scorer: {field: {n, true, rate} | {n, mean}}}``.
    scorers: dict[str, dict[str, dict[str, float]]] | None = None
    #: Every scorer's declared metrics, per slice: ``{scorer: ScorerMetrics}``.
    metrics: dict[str, ScorerMetrics] | None = None
    #: Why answers failed (:mod:`povagent.scoring.diagnostics_breakdown`), an addition.
    diagnostics: Diagnostics | None = None
    #: Keys whose parse holds a NaN coordinate (their official mean is NaN, as officially).
    nan_coordinate_rows: list[str] | None = None
    #: The run's keys and what their rows cost (``None`` in ``rescore``'s summary of re-parsed rows).
    rows: RowCounts | None = None
    usage: UsageTotals | None = None
    #: ``rescore``'s: the run re-parsed, the parser, the rows, rows by parse status, and how
    #: many answers the parser repaired.
    source_run: str | None = None
    parser: str | None = None
    n_rows: int | None = None
    parse_status: dict[str, int] | None = None
    repaired: int | None = None
    pipeline: PipelineNames | None = None
    #: Every selected key has a row.
    complete: bool | None = None
    interrupted: bool | None = None
    #: What stopped the run early (a signal, a budget), or ``None``.
    stopped: str | None = None
    #: This session's request, cache, journal and timing counters (``RunStats``).
    session: SessionCounters | None = None
    #: The image store's counters.
    images: ImageCounters | None = None
