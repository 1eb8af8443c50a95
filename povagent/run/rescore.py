"""Re-parse and re-score a finished run offline, with another parser: no model is called.

Every row keeps its raw answer(s), so a run can be read again: for each row of
``RUN_DIR/results.jsonl`` the final raw answer is parsed with the named parser against the
answer schema the run's strategy asked for (rebuilt from the strategy, without images when it
offers ``answer_spec(instance)``), scored with the run's scorers by the score step the runner
uses (:mod:`povagent.run.score_step`: the instance as the model saw it, the same status and
prediction rules) against the set read by the loader the runner chooses
(:func:`~povagent.dataset.evaluation_set.open_evaluation_set`), summarized as the runner
summarizes (with the run's own parser, rows and ``summary.json`` sections come out as the run's), and written to
``RUN_DIR/rescored-<parser>/`` (``results.jsonl``, ``summary.json``, ``config.yaml``). The
original run is never modified. Rows without an answer (infrastructure errors) are kept as is.
The new rows are staged and replace the folder's ``results.jsonl`` in one move once all are
rescored (:class:`~povagent.results.rows.StagedResults`: one fsync, not one a row), so a rescore
killed at any moment leaves the previous complete file or none, never part of the new one; the
summary is written last.

The parser defaults to ``official``: ``rescore RUN`` turns any run into paper-comparable numbers.
With a lenient parser each row also gets its official reading (see
:mod:`povagent.results.official_reading`) and the summary its ``official_parse`` beside. Rows
whose official reading holds a NaN coordinate are named in a warning (the official mean of any
slice holding one is NaN).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import yaml

from povagent.answers.spec import AnswerSpec
from povagent.config.plugin_checks import parser_misfit
from povagent.config.plugin_rule import missing_plugin_message
from povagent.dataset.evaluation_set import open_evaluation_set
from povagent.dataset.instances import Instance
from povagent.errors import DatasetError, PluginError, PredictionsError
from povagent.exchange.images import ImageStore
from povagent.files.confined_write import ConfinedFolder, write_inside
from povagent.plugins import PluginHost, get_plugin_host
from povagent.results.finished_run import RESULTS_FILE, FinishedRun
from povagent.results.official_reading import (
    OFFICIAL_PARSER,
    nan_rows,
    nan_warning,
    official_counterpart,
    officially_read,
)
from povagent.results.rows import ResultRow, RowStatus, StagedResults
from povagent.run.pending import asked_by
from povagent.run.run_folder import read_run_config
from povagent.run.score_step import AnswerScoring, question_category, question_main_category
from povagent.run.summary import declared_metrics, summarize_rows, write_summary
from povagent.run.summary_model import RunSummary
from povagent.scoring.score_protocols import scorer_protocols


@dataclass
class RescoreResult:
    """Where the rescored run went, its summary, and rows that could not be rescored."""

    out_dir: Path
    #: The rescored folder's ``summary.json``, as the type it is.
    summary: RunSummary
    warnings: list[str] = field(default_factory=list)


def answer_spec_for(strategy: Any, instance: Instance, images: ImageStore) -> AnswerSpec:
    """What ``strategy`` asked for ``instance``: its ``answer_spec(instance)`` when it has one,
    else the answer of the request it builds (which may read the frames, never a model)."""
    cheap = getattr(strategy, "answer_spec", None)
    if callable(cheap):
        spec = cheap(instance)
        if isinstance(spec, AnswerSpec):
            return spec
    return strategy.build(instance, images).answer


def rescore_row(row: ResultRow, instance: Instance, spec: AnswerSpec, scoring: AnswerScoring, parser_name: str) -> ResultRow:
    """``row`` re-parsed from its final raw answer and re-scored by the score step the runner
    uses (:mod:`povagent.run.score_step`); infrastructure errors are kept as they are."""
    raw = row.raw_response
    # the categories are the instance's, whatever the row recorded
    categories = {"category": question_category(instance), "main_category": question_main_category(instance)}
    if row.status is RowStatus.INFRA_ERROR or raw is None:
        return row.model_copy(update={"parser": parser_name, "official_reading": None, **categories})
    scored = scoring.score_answer(instance, spec, raw)
    return row.model_copy(
        update={
            "parser": parser_name,
            "parse": scored.parse,
            "status": scored.status,
            "prediction": scored.prediction,
            "scores": scored.scores,
            "official_reading": scored.official_reading,
            **categories,
        }
    )


def rescore_summary(rows: list[ResultRow], scorers: Mapping[str, Any]) -> dict[str, Any]:
    """The rescored rows' summary: the run's own (:func:`~povagent.run.summary.summarize_rows`,
    with ``scorers``' declared metrics), with the rows by parse status and how many answers the
    parser repaired."""
    summary = summarize_rows(rows, None, declared_metrics(scorers), scorer_protocols(scorers))
    summary["parse_status"] = dict(Counter(str(r.parse.status) if r.parse else str(r.status) for r in rows))
    summary["repaired"] = sum(1 for r in rows if r.parse is not None and r.parse.repair)
    return summary


def _raise(exc: BaseException, *_: Any) -> None:
    """A plugin that raises stops a rescore: it rewrites a finished run, and keeps the previous
    rescore rather than write one with holes."""
    raise exc


def official_reading_of_run(host: PluginHost, run_parser: str | None) -> str:
    """The parser giving a run's official reading: its own parser when that parser reads as the
    official runner does (``reproduces_official``: the ``active`` mode's tool-call reader, the
    ``robopoint-official`` reading), else ``official``. A run's parser that no loaded plugin
    registers falls back to ``official``."""
    if run_parser and run_parser != OFFICIAL_PARSER and run_parser in host.names("parser"):
        if getattr(host.parser(run_parser, {}), "reproduces_official", False):
            return run_parser
    return OFFICIAL_PARSER


def rescore_run(
    run_dir: str | Path,
    parser_name: str | None = None,
    *,
    dataset_root: str | Path | None = None,
    host: PluginHost | None = None,
    plugins: Sequence[str] = (),
    extra_scorers: Sequence[str] = (),
) -> RescoreResult:
    """Re-parse every row of a finished run with ``parser_name`` (default: the official reading,
    see :func:`official_reading_of_run`) and re-score it (offline) with the run's scorers plus ``extra_scorers`` (names, default
    options; e.g. ``diagnose`` and ``relation``, whose figures go to the summary's
    ``diagnostics``).

    A run folder is untrusted: the ``plugins:`` its ``config.yaml`` names are never imported.
    The plugins come from ``plugins`` (what ``--plugin`` names on the command line); a strategy
    or scorer of the run that none of them registers is a :class:`PluginError` saying which
    plugin to pass (see :func:`~povagent.config.plugin_rule.missing_plugin_message`).
    """
    run = Path(run_dir)
    results = run / RESULTS_FILE
    if not results.exists():
        raise PredictionsError(f"{results}: not found (is {run} a run folder?)")
    finished = FinishedRun.open(run)  # the one reader of a run folder: the report's, export's and compare's
    config = read_run_config(run, finished.config_bytes)
    host = host or get_plugin_host(tuple(plugins))
    # the parser is named on the command line (the host says if it is unknown); the run's
    # strategy and scorers come from its folder
    for kind, name in [("strategy", config.strategy.name), *(("scorer", s.name) for s in config.scorers)]:
        if name not in host.names(kind):
            raise PluginError(missing_plugin_message("rescore", run, kind, name, config.plugins))
    if parser_name is None:
        parser_name = official_reading_of_run(host, config.parser.name if config.parser else None)
    misfit = parser_misfit(host, config.strategy.name, parser_name)
    if misfit is not None:
        raise PluginError(f"rescore {run}: {misfit}")
    parser = host.parser(parser_name, {})
    counterpart = official_counterpart(parser)
    official = (host.parser(counterpart, {}), counterpart) if counterpart else None
    strategy = host.strategy(config.strategy.name, config.strategy.options)
    scorers = {s.name: host.scorer(s.name, s.options) for s in config.scorers}
    for name in extra_scorers:
        if name not in scorers:
            scorers[name] = host.scorer(name, {})
    root = Path(dataset_root) if dataset_root is not None else config.dataset.root
    if dataset_root is None and not root.is_absolute() and not root.exists():
        # relative paths in a pipeline are relative to the directory the run was started from
        raise DatasetError(
            f"{run / 'config.yaml'} names the dataset by the relative path {str(root)!r}, which is not "
            f"found from {Path.cwd()}: run rescore from the directory the run was made in, or pass --dataset"
        )
    dataset = asked_by(  # answers are re-read, not re-sent
        config,
        open_evaluation_set(root, check_images=False, format=config.dataset.format, images=config.dataset.images, options=config.dataset.options, host=host),
    )
    official_parser, official_name = official if official is not None else (None, None)
    scoring = AnswerScoring(
        parser,
        scorers,
        dataset,
        official_parser,
        official_name,
        on_parser_error=_raise,
        on_scorer_error=lambda _name, exc: _raise(exc),
        answer_type=host.answer_type(strategy.answer_type),
    )
    images = ImageStore()
    warnings: list[str] = []
    out_dir = run / f"rescored-{parser_name}"
    rows_out: list[ResultRow] = []
    # The folder is replaced whole: the rows are staged and published in one move only once
    # every row is rescored, so a rescore killed at any moment leaves the previous complete
    # folder (or none), never some of the new rows or a row twice (see StagedResults).
    # The run folder is the one the user named: ``rescored-*`` and every file in it are opened
    # below it without following a link planted there (see confined_write).
    with StagedResults(out_dir / "results.jsonl", root=run) as staged:
        for row in finished.all_rows():
            instance = dataset.instance(row.instance_id)
            if instance is None:
                warnings.append(f"{row.key}: instance {row.instance_id} is not in the dataset {root}; row left out")
                continue
            spec = answer_spec_for(strategy, instance, images)
            new = rescore_row(row, instance, spec, scoring, parser_name)
            staged.write(new)
            rows_out.append(new)
        nan_note = nan_warning(nan_rows(officially_read(r) for r in rows_out))
        if nan_note:
            warnings.append(nan_note)
        summary = {"source_run": str(run), "parser": parser_name, "n_rows": len(rows_out), **rescore_summary(rows_out, scorers)}
        rescored_config = config.resolved_dict()
        rescored_config["parser"] = {"name": parser_name, "options": {}}
        rescored_config["scorers"] = [*rescored_config.get("scorers", []), *({"name": n, "options": {}} for n in extra_scorers
                                                                              if n not in {s.name for s in config.scorers})]
        # an earlier rescore's summary and config must never stand beside these rows: gone
        # before the rows land; the summary comes last, so a folder with one is complete
        with ConfinedFolder(run, out_dir.name) as folder:
            for name in ("summary.json", "config.yaml"):
                folder.unlink(name)
        staged.commit()
    write_inside(run, f"{out_dir.name}/config.yaml", yaml.safe_dump(rescored_config, sort_keys=False))
    return RescoreResult(out_dir, write_summary(out_dir / "summary.json", summary, root=run), warnings)
