"""Re-parse and re-score a finished run offline, with another parser: no model is called.

Every row keeps its raw answer(s), so a run can be read again: for each row of
``RUN_DIR/results.jsonl`` the final raw answer is parsed with the named parser against the
answer schema the run's strategy asked for (rebuilt from the strategy, without images when it
offers ``answer_spec(instance)``), scored with the run's scorers, and written to
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
from typing import Any, Sequence

import yaml

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.config.plugin_rule import missing_plugin_message
from povagent.dataset.instances import Instance
from povagent.dataset.loader import Dataset, load_dataset
from povagent.errors import DatasetError, PluginError, PredictionsError
from povagent.exchange.images import ImageStore
from povagent.plugins import PluginHost, get_plugin_host
from povagent.results.official_reading import (
    OFFICIAL_PARSER,
    nan_rows,
    nan_warning,
    official_counterpart,
    official_parse_breakdown,
    officially_read,
    read_officially,
)
from povagent.results.rows import Prediction, ResultRow, RowStatus, StagedResults, read_rows
from povagent.run.confined_read import check_regular
from povagent.run.confined_write import ConfinedFolder, write_inside
from povagent.run.run_folder import read_run_config
from povagent.run.summary import diagnosed_row, write_summary
from povagent.run.summary_model import RunSummary
from povagent.scoring.breakdown import ScoredRow, breakdown
from povagent.scoring.diagnostics_breakdown import diagnostics_breakdown
from povagent.scoring.official import scoring_frame


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


def prediction_of(instance: Instance, parsed: ParsedAnswer) -> Prediction:
    """The prediction as scored: pixels, and for A/B the selected frame's ``image_path``."""
    frame = scoring_frame(instance, parsed.selected_image) if parsed.answered else None
    image_path = frame.image_path if frame is not None and instance.condition.uses_exploration_frames else None
    return Prediction(selected_image=parsed.selected_image, image_path=image_path, x=parsed.x, y=parsed.y)


def rescore_row(
    row: ResultRow,
    instance: Instance,
    spec: AnswerSpec,
    parser: Any,
    parser_name: str,
    scorers: dict[str, Any],
    dataset: Dataset,
    official: tuple[Any, str] | None = None,
) -> ResultRow:
    """``row`` re-parsed from its final raw answer and re-scored (infra errors kept as they are).

    ``official`` is ``(parser, name)`` of the official reading to keep beside a lenient
    ``parser``'s (``None``: ``parser`` reads officially, the row keeps no second reading).
    """
    raw = row.raw_response
    if row.status is RowStatus.INFRA_ERROR or raw is None:
        return row.model_copy(update={"parser": parser_name, "official_reading": None})

    def score(parsed: ParsedAnswer) -> dict[str, dict[str, Any]]:
        return {name: scorer.score(instance, parsed, dataset) for name, scorer in scorers.items()}

    parsed = parser.parse(raw, spec)
    scores = score(parsed)
    reading = read_officially(official[0], official[1], raw, spec, parsed, scores, score) if official else None
    return row.model_copy(
        update={
            "parser": parser_name,
            "parse": parsed,
            "status": RowStatus.ANSWERED if parsed.answered else RowStatus.PARSE_ERROR,
            "prediction": prediction_of(instance, parsed),
            "scores": scores,
            "official_reading": reading,
        }
    )


def summarize_rows(rows: list[ResultRow], scorer_name: str = "official") -> dict[str, Any]:
    """The official breakdown of rescored rows (from ``scores[scorer_name]``), with parse counts."""
    from povagent.scoring.evaluations import official_parse_error

    scored = []
    for row in rows:
        s = row.scores.get(scorer_name, {})
        scored.append(
            ScoredRow(
                row.condition, row.direction, bool(s.get("answered")), s.get("l2"), s.get("gt_in_frame"), s.get("l2_strict"), row.run,
                s.get("error_x"), s.get("error_y"), official_parse_error(row) is not None,
            )
        )
    summary = breakdown(scored)
    readings = [r.official_reading.parser for r in rows if r.official_reading is not None]
    if readings and scorer_name == "official":  # parsed leniently: the paper-comparable reading beside
        from povagent.run.summary import scored_row

        summary["official_parse"] = official_parse_breakdown(
            [scored_row(officially_read(r), scorer_name) if r.official_reading is not None else s
             for r, s in zip(rows, scored) if r.official_reading is not None or r.status is RowStatus.INFRA_ERROR],
            readings[0],
            sum(1 for r in rows if r.official_reading is None and r.status is not RowStatus.INFRA_ERROR),
        )
    diagnostics = diagnostics_breakdown(d for d in (diagnosed_row(r) for r in rows) if d is not None)
    if diagnostics is not None:  # an addition, beside the official breakdown
        summary["diagnostics"] = diagnostics
    summary["parse_status"] = dict(Counter(str(r.parse.status) if r.parse else str(r.status) for r in rows))
    summary["repaired"] = sum(1 for r in rows if r.parse is not None and r.parse.repair)
    return summary


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
    results = run / "results.jsonl"
    if not results.exists():
        raise PredictionsError(f"{results}: not found (is {run} a run folder?)")
    check_regular(results, what="results file")  # a pipe or a device planted there: one line
    config = read_run_config(run)
    host = host or get_plugin_host(tuple(plugins))
    # the parser is named on the command line (the host says if it is unknown); the run's
    # strategy and scorers come from its folder
    for kind, name in [("strategy", config.strategy.name), *(("scorer", s.name) for s in config.scorers)]:
        if name not in host.names(kind):
            raise PluginError(missing_plugin_message("rescore", run, kind, name, config.plugins))
    if parser_name is None:
        parser_name = official_reading_of_run(host, config.parser.name if config.parser else None)
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
    dataset = load_dataset(root, check_images=False)  # answers are re-read, not re-sent
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
        for row in read_rows(results):
            instance = dataset.instance(row.instance_id)
            if instance is None:
                warnings.append(f"{row.key}: instance {row.instance_id} is not in the dataset {root}; row left out")
                continue
            spec = answer_spec_for(strategy, instance, images)
            new = rescore_row(row, instance, spec, parser, parser_name, scorers, dataset, official)
            staged.write(new)
            rows_out.append(new)
        nan_note = nan_warning(nan_rows(officially_read(r) for r in rows_out))
        if nan_note:
            warnings.append(nan_note)
        scorer_name = "official" if "official" in scorers else next(iter(scorers), "official")
        summary = {"source_run": str(run), "parser": parser_name, "n_rows": len(rows_out), **summarize_rows(rows_out, scorer_name)}
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
