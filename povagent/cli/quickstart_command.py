"""``povagent quickstart``: generate a small dataset, sweep the offline baselines, report."""

from __future__ import annotations

from pathlib import Path

import typer

from povagent.cli import app


@app.command("quickstart")
def quickstart_command(
    out: Path = typer.Option(
        Path("povagent-quickstart"), "--out", metavar="FOLDER", help="Folder for the dataset, the sweep and the report."
    ),
    dataset: Path | None = typer.Option(
        None, "--dataset", metavar="FOLDER", help="Use this dataset folder instead of generating one."
    ),
    houses: int = typer.Option(3, "--houses", min=1, metavar="N", help="Houses to generate."),
    seed: int = typer.Option(0, "--seed", metavar="N", help="Random seed of the generator."),
    jobs: int | None = typer.Option(
        None, "--jobs", min=1, metavar="N", help="Worker processes generating the houses (default: one per core, at most one per house)."
    ),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Do not show progress bars."),
) -> None:
    """Try everything offline: generate, run the baselines, report.

    Generates about three houses, runs the center, random and oracle baselines on conditions
    A, B and C, and writes the report. Running it again resumes: no work is repeated.
    """
    from povagent.report.quickstart import run_quickstart

    result = run_quickstart(out, dataset, houses=houses, seed=seed, jobs=jobs, quiet=quiet, say=typer.echo)
    typer.echo("")
    typer.echo(result.main_table_markdown)
    typer.echo(f"report: {result.report}")
    typer.echo(f"sweep:  {result.sweep} (run the same command again: it resumes, zero new work)")
