"""The ``generate`` command: write a POVBench-format dataset of procedural houses."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from povagent.cli import app


@app.command("generate")
def generate_command(
    out: Path = typer.Option(..., "--out", help="Folder to write the dataset to (release layout)."),
    houses: int = typer.Option(3, "--houses", min=1, help="Number of houses."),
    seed: int = typer.Option(0, "--seed", help="Seed: the same seed gives byte-identical files."),
    frames: int = typer.Option(30, "--frames", min=1, help="Exploration frames per house (at most; the paper uses 30)."),
    jobs: int = typer.Option(1, "--jobs", min=1, help="Worker processes (the output does not depend on it)."),
    with_render: bool = typer.Option(
        False, "--with-render", help="Also write depth maps and instance masks under each house's _render/."
    ),
    judge: str | None = typer.Option(
        None, "--judge", help="Surface judge as module:Name (a VLM judge, say); default: the physical rules."
    ),
) -> None:
    """Generate houses, render their exploration frames and observer views, write the queries."""
    from povagent.generate import generate_dataset
    from povagent.generate.judge import load_judge

    report = generate_dataset(
        out,
        houses=houses,
        seed=seed,
        frames=frames,
        jobs=jobs,
        progress=sys.stdout.isatty(),
        with_render=with_render,
        judge=load_judge(judge) if judge else None,
    )
    shares = ", ".join(f"{d} {100 * s:.0f}%" for d, s in report.direction_shares().items())
    typer.echo(
        f"{out}: {len(report.houses)} houses, {report.pairs} pairs, "
        f"{report.instances_per_condition} instances per condition ({shares} of pairs), "
        f"{report.renders} frames in {report.seconds:.1f} s"
    )
