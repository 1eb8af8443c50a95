"""Commands on datasets and prediction files: ``validate`` and ``score``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from povagent.cli import app
from povagent.cli.console_width import PathTitle
from povagent.cli.format_option import FormatsInHelp, format_option
from povagent.cli.options import strict_option
from povagent.cli.slice_rows import breakdown_slices

if TYPE_CHECKING:
    from povagent.run.summary_model import Breakdown, Cell, ScoreSummary

@app.command("validate", cls=FormatsInHelp)
def validate_command(
    dataset_dir: Path = typer.Argument(..., metavar="DATASET_DIR",
                                       help="Dataset folder: a POVBench release, a generated or a real-world set (with --format: the set's file)."),
    width: int = typer.Option(512, "--width", min=1, metavar="PIXELS", help="Width every exploration frame must have."),
    height: int = typer.Option(512, "--height", min=1, metavar="PIXELS", help="Height every exploration frame must have."),
    format: str | None = format_option("The set's dataset format (default: the folder's own, as a run reads it: a real-world set by its "
                                       "realworld.json, any other folder in the POVBench release layout)."),
    images: Path | None = typer.Option(None, "--images", metavar="DIR",
                                       help="With --format: the folder the set's image paths are relative to (default: the file's)."),
    frame_cache: Path | None = typer.Option(None, "--frame-cache", metavar="DIR",
                                            help="With a video set (--format vsibench): the folder keeping the videos' sampled frames across "
                                                 "runs, as a pipeline's dataset.options.cache_dir (default: none, every video decoded)."),
) -> None:
    """Check every file and image of a dataset; list every problem.

    Each problem names the file, the JSON path (or line, or record) and what is wrong with it.
    Exit code 1 when there is any. Warnings (on stderr) leave the dataset valid.
    """
    from povagent.dataset.evaluation_set import format_of
    from povagent.dataset.formats import FormatRead
    from povagent.dataset.problems import Problem
    from povagent.errors import DatasetError

    warnings: list[Problem] = []
    try:  # no --format: the folder's own, as the runner reads it (a real-world set, a release)
        found = format_of(dataset_dir, format)
    except DatasetError as exc:
        problems = [Problem(str(dataset_dir), "", str(exc).removeprefix(f"{dataset_dir}: "))]
    else:
        options: dict[str, Any] = {k: v for k, v in (("width", width), ("height", height)) if k in found.option_names}  # a release's frames
        if frame_cache is not None:
            if "cache_dir" not in found.option_names:
                raise typer.BadParameter(f"the {found.key} format reads no video: it keeps no frames", param_hint="--frame-cache")
            options["cache_dir"] = str(frame_cache)
        problems = found.problems_of(FormatRead(dataset_dir, images=images, options=options, warnings=warnings))
    for w in warnings:
        typer.echo(f"warning: {w}", err=True)
    for p in problems:
        typer.echo(_fit_to_terminal(str(p)))
    if problems:
        typer.echo(f"{len(problems)} problem(s) in {dataset_dir}", err=True)
        raise typer.Exit(1)
    typer.echo(f"{dataset_dir}: valid")


def _fit_to_terminal(line: str) -> str:
    """``line`` wrapped to the terminal's width, continuation lines indented, when stdout is a
    terminal; unchanged when it is a pipe or a file, where one problem a line is what grep and
    scripts read."""
    import shutil
    import sys
    import textwrap

    if not sys.stdout.isatty():
        return line
    width = shutil.get_terminal_size((80, 24)).columns
    # a JSON path or file name longer than the line is left whole: the terminal breaks it
    return textwrap.fill(line, width, subsequent_indent="    ", break_long_words=False, break_on_hyphens=False)


def render_summary(summary: Breakdown, title: str | PathTitle = "POVBench scores") -> None:
    """Print a summary (overall / per condition / per direction) as a rich table.

    A :class:`~povagent.cli.console_width.PathTitle` has its path shortened to fit.

    Several runs: the rows are the mean of per-run means (the paper's numbers), said in the
    caption, and a last row gives the pooled overall mean, labelled ``pooled``.
    """
    from rich.console import Console

    from povagent.cli.console_width import fitted_table
    from povagent.cli.numbers import format_number

    runs = summary.runs
    caption = f"mean of per-run means over {len(runs)} runs (the paper's aggregation); n / total summed over runs" if len(runs) > 1 else None
    rows: list[list[str]] = []

    def add(name: str, cell: Cell) -> None:
        rr = cell.response_rate
        pif = cell.pct_in_frame
        rows.append(
            [
                name,
                format_number(cell.mean_l2),
                format_number(cell.std_l2),
                "-" if rr is None else f"{100 * rr:.1f}%",
                "-" if pif is None else f"{pif:.1f}%",
                format_number(cell.mean_l2_strict),
                f"{cell.n} / {cell.n_total}",
            ]
        )

    for name, cell in breakdown_slices(summary):
        add(name, cell)
    if summary.pooled is not None:
        add(f"overall, pooled ({len(runs)} runs in one mean)", summary.pooled.overall)
    columns = [("slice", "label")] + [(h, "number") for h in ("mean L2", "std", "resp. rate", "GT in frame", "strict L2", "n / total")]
    Console().print(fitted_table(columns, rows, title=title, caption=caption))

#: The keys of a breakdown that ``score --json`` prints.
SCORE_JSON_KEYS = (
    "overall",
    "per_condition",
    "per_direction",
    "per_condition_direction",
    "aggregation",
    "runs",
    "per_run",
    "pooled",
    "run_folders",
    "n_parse_error",
    "counting",
    "metrics",
)


def _score_json(summary: dict[str, Any]) -> dict[str, Any]:
    if "models" in summary:
        return {"models": {m: _score_json(s) for m, s in summary["models"].items()}}
    return {k: summary[k] for k in SCORE_JSON_KEYS if k in summary}


@app.command("score")
def score_command(
    predictions: Path = typer.Option(
        ...,
        "--predictions",
        metavar="PATH",
        help="The predictions: an official prediction file (a list of rows or {metadata, predictions}), "
        "a folder of them, a folder of MODEL_RUN folders (as the authors' runner names them), or a povagent "
        "run folder or results.jsonl.",
    ),
    dataset: Path = typer.Option(..., "--dataset", metavar="FOLDER", help="Dataset folder in the POVBench release layout."),
    as_json: bool = typer.Option(False, "--json", help="Print the scores as JSON instead of tables."),
    strict: bool = strict_option(),
    counting: str = typer.Option(
        "official",
        "--counting",
        metavar="official|povagent",
        help="official (default): official prediction rows are counted exactly as the official scorer counts them "
        "(pair ids as written, log paths as written, every pair it can read); povagent: against the pairs and frames "
        "povagent's loader accepts (see docs/explanation/official.md).",
    ),
) -> None:
    """Score predictions with the official metric.

    The mean L2 error over answered instances, with the response rate beside it, counted
    exactly as the official scorer counts. Several runs are averaged per run (the paper's
    number), the pooled mean shown beside it, labelled.
    """
    from povagent.dataset.loader import load_dataset
    from povagent.plugins import get_plugin_host
    from povagent.results.prediction_files import score_predictions
    from povagent.run.summary_model import ScoreSummary
    from povagent.scoring.official_release import read_release
    from povagent.scoring.score_protocols import following, registered_protocols

    if counting not in ("official", "povagent"):
        typer.echo(f"error: --counting must be official or povagent (got {counting!r})", err=True)
        raise typer.Exit(2)
    ds = load_dataset(dataset, strict=strict, check_images=False)  # scoring needs the ground truth, not the pixels
    release = read_release(dataset) if counting == "official" else None
    for p in ds.problems:
        # under official counting the official rows still see such a pair as the official scorer does
        how = " by povagent's loader (official rows are counted against the release as officially)" if release is not None else ""
        typer.echo(f"warning: dataset problem, skipped{how}: {p}", err=True)
    # the official metric is the normalized_l2 scorer's: its declared metrics over the fields it
    # gives each point, as run and rescore report them
    official = following(registered_protocols(), "normalized_l2")
    scorers = {official: get_plugin_host().scorer(official)} if official is not None else {}
    summary, warnings = score_predictions(predictions, ds, release, scorers)
    # the release's own (its exploration logs are read as predictions name their houses)
    for w in release.warnings if release is not None else []:
        typer.echo(f"warning: {w}", err=True)
    summary["counting"] = counting
    for w in warnings[:20]:
        typer.echo(f"warning: {w}", err=True)
    if len(warnings) > 20:
        typer.echo(f"warning: ... and {len(warnings) - 20} more", err=True)
    if as_json:
        typer.echo(json.dumps(_score_json(summary), indent=2))
    elif "models" in summary:
        for model, model_summary in summary["models"].items():
            _render_score(ScoreSummary.model_validate(model_summary), f"POVBench scores: {model}")
    else:
        _render_score(ScoreSummary.model_validate(summary), "POVBench scores")


def _render_score(summary: ScoreSummary, title: str) -> None:
    """The official table, then the declared metrics' table (every one the official scorer
    declares, with its CI: the extras the official table has no column for)."""
    from povagent.cli.metrics_table import render_metrics

    render_summary(summary, title=title)
    render_metrics(summary, title)
