"""Commands ``report``, ``export`` and ``compare``: thin wrappers over :mod:`povagent.report`."""

from __future__ import annotations

from pathlib import Path

import typer

from povagent.cli import app


@app.command("report")
def report_command(
    source: Path = typer.Argument(
        ..., metavar="SOURCE", help="A run folder (with results.jsonl) or a sweep folder (with sweep.json and its run folders)."
    ),
    out: Path | None = typer.Option(None, "--out", metavar="FOLDER", help="Folder to write the report to (default: SOURCE/report)."),
    dataset: Path | None = typer.Option(
        None, "--dataset", metavar="FOLDER", help="Dataset folder, if not the one named in the runs' config.yaml."
    ),
    bootstrap: int = typer.Option(
        2000, "--bootstrap", min=0, metavar="N", help="Bootstrap resamples per confidence interval (0: no intervals)."
    ),
    gallery_limit: int | None = typer.Option(
        None, "--gallery-limit", min=0, metavar="N",
        help="At most N gallery rows per system (default: every instance of the first run).",
    ),
    no_gallery: bool = typer.Option(False, "--no-gallery", help="Draw no gallery images (faster)."),
    workers: int | None = typer.Option(
        None, "--workers", min=1, metavar="N", help="Threads drawing gallery images (default: one per core, at most 4)."
    ),
    pool: bool = typer.Option(
        False, "--pool", help="Pool runs of the same name into one system (default: every run folder is its own system)."
    ),
) -> None:
    """Write the paper's tables, plots and an HTML report.

    Tables in Markdown, CSV and LaTeX, plots, and one self-contained HTML page with a
    gallery of the predictions drawn on their frames. Each run folder (each sweep cell) is one
    system, named by its config's label: or its model; runs are pooled only with --pool or a
    shared label:, and the report says so.
    """
    from povagent.report.build import write_report
    from povagent.report.leaderboard import LEADERBOARD
    from povagent.report.tables import to_markdown

    result = write_report(
        source, out, dataset, n_boot=bootstrap, gallery_limit=gallery_limit, gallery=not no_gallery, workers=workers, pool=pool
    )
    for pooling in result.poolings:
        typer.echo(f"note: {pooling.note()}", err=True)
    if result.dataset_note:
        typer.echo(f"warning: no center baseline, counting-non-responses variant or gallery images: {result.dataset_note}", err=True)
    typer.echo(to_markdown(result.tables[0]))
    for table in result.tables[1:]:
        if table.key == LEADERBOARD:  # choice runs: the sets side by side, the numbers a reader came for
            typer.echo(to_markdown(table))
    g = result.gallery
    if g is not None:
        typer.echo(f"gallery: {g.entries} predictions, {g.drawn} images drawn, {g.cached} reused, {g.without_image} without a frame")
    typer.echo(f"tables: {result.out / 'tables'}  (tables.md, tables.tex)")
    typer.echo(f"report: {result.page}  ({result.timings['total']:.1f} s)")


@app.command("export")
def export_command(
    run_dir: Path = typer.Argument(
        ..., metavar="RUN_DIR", help="A run folder (with results.jsonl); for long-csv also a sweep folder."
    ),
    format: str = typer.Option(
        "official", "--format", metavar="FORMAT",
        help="official: POVBench's prediction rows (one file per run index). long-csv: the all_runs_long.csv "
        "of the authors' aggregate_runs.py, one line per model, run (numbered from 1) and item.",
    ),
    out: Path | None = typer.Option(
        None, "--out", metavar="PATH",
        help="Where to write (default: RUN_DIR/official_predictions.json, or a folder of run_K.json files "
        "when there are several runs; RUN_DIR/all_runs_long.csv for long-csv).",
    ),
    run: int | None = typer.Option(None, "--run", metavar="K", help="Export only run K."),
    dataset: Path | None = typer.Option(
        None, "--dataset", metavar="FOLDER",
        help="Dataset folder, for candidate_images and the long CSV's ground truth (default: the one in config.yaml).",
    ),
    model: str | None = typer.Option(
        None, "--model", metavar="LABEL", help="long-csv only: the model label of a run folder's lines (default: its model)."
    ),
) -> None:
    """Write a run's predictions in the official formats.

    Official prediction rows, or the long CSV. The official rows are what the authors' evaluation code reads; the long CSV is the one
    their aggregate_runs.py writes, so existing analysis notebooks keep working.
    """
    from povagent.errors import PredictionsError
    from povagent.report.export import export_long_csv, export_run

    if format == "long-csv":
        typer.echo(f"wrote {export_long_csv(run_dir, out, dataset_path=dataset, model=model, run=run)}")
        return
    if format != "official":
        raise PredictionsError(f"--format {format!r}: unknown export format (supported: official, long-csv)")
    if model is not None:
        raise PredictionsError("--model labels the long CSV's lines; use it with --format long-csv")
    for path in export_run(run_dir, out, run, dataset):
        typer.echo(f"wrote {path}")


@app.command("compare")
def compare_command(
    run_a: Path = typer.Argument(..., metavar="RUN_A", help="Run folder A, the reference."),
    run_b: Path = typer.Argument(..., metavar="RUN_B", help="Run folder B, compared with A."),
    top: int = typer.Option(15, "--top", min=0, metavar="N", help="How many of the most changed instances to list."),
    out: Path | None = typer.Option(
        None, "--out", metavar="FOLDER", help="Also write compare.html, with both runs' predictions drawn, to this folder."
    ),
    dataset: Path | None = typer.Option(
        None, "--dataset", metavar="FOLDER", help="Dataset folder for the HTML's images (default: the one in config.yaml)."
    ),
    bootstrap: int = typer.Option(2000, "--bootstrap", min=0, metavar="N", help="Bootstrap resamples per confidence interval."),
) -> None:
    """Compare two runs instance by instance.

    Paired statistics over the instances both runs answered, and the instances whose error
    changed most.
    """
    from povagent.report.collect import collect
    from povagent.report.compare import compare_runs, print_comparison, write_comparison_html
    from povagent.report.run_sets import load_collection_dataset

    cmp = compare_runs(run_a, run_b, n_boot=bootstrap)
    print_comparison(cmp, top)
    if out is not None:
        ds, note = load_collection_dataset(collect(run_a), dataset)
        if ds is None:
            typer.echo(f"warning: no frames in the HTML: {note}", err=True)
        typer.echo(f"compare: {write_comparison_html(cmp, out, ds)}")
