"""``povagent quickstart``: generate a small dataset, sweep the offline baselines, report."""

from __future__ import annotations

from pathlib import Path

import typer

from povagent.cli import app


@app.command("quickstart")
def quickstart_command(
    out: Path = typer.Option(Path("povagent-quickstart"), "--out", help="Folder for the dataset, the sweep and the report."),
    dataset: Path | None = typer.Option(None, "--dataset", help="Use this dataset instead of generating one."),
    houses: int = typer.Option(3, "--houses", help="Houses to generate."),
    seed: int = typer.Option(0, "--seed", help="Generator seed."),
    jobs: int = typer.Option(2, "--jobs", help="Processes for generation."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bars."),
) -> None:
    """The main job, offline: generate ~3 houses, run center/random/oracle on A, B and C, report."""
    from povagent.run.quickstart import run_quickstart

    result = run_quickstart(out, dataset, houses=houses, seed=seed, jobs=jobs, quiet=quiet, say=typer.echo)
    typer.echo("")
    typer.echo(result.main_table_markdown)
    typer.echo(f"report: {result.report}")
    typer.echo(f"sweep:  {result.sweep} (run the same command again: it resumes, zero new work)")
