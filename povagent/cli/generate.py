"""The ``generate`` command: write a POVBench-format dataset of procedural houses."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import typer

from povagent.cli import app


def judge_options(pairs: list[str]) -> dict[str, Any]:
    """``["model=gpt-5.4", "temperature=0"]`` -> ``{"model": "gpt-5.4", "temperature": 0}``.

    Values are read as YAML scalars, as the same options would be in a pipeline file.
    """
    import yaml

    options: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip():
            raise typer.BadParameter(f"{pair!r}: give it as KEY=VALUE", param_hint="--judge-option")
        try:
            options[key.strip()] = yaml.safe_load(value) if value.strip() else ""
        except yaml.YAMLError:
            options[key.strip()] = value
    return options


@app.command("generate")
def generate_command(
    out: Path = typer.Option(..., "--out", metavar="FOLDER", help="Folder to write the dataset to (POVBench release layout)."),
    houses: int = typer.Option(3, "--houses", min=1, metavar="N", help="Number of houses."),
    seed: int = typer.Option(0, "--seed", metavar="N", help="Random seed: the same seed writes byte-identical files."),
    frames: int = typer.Option(
        30, "--frames", min=1, metavar="N", help="Exploration frames per house, at most (the paper uses 30)."
    ),
    jobs: int | None = typer.Option(
        None, "--jobs", min=1, metavar="N",
        help="Worker processes (default: one per core, at most one per house; the files written do not depend on it).",
    ),
    with_render: bool = typer.Option(
        False, "--with-render", help="Also write depth maps and instance masks under each house's _render/ folder."
    ),
    judge: str = typer.Option(
        "physical-rules", "--judge", metavar="NAME",
        help="Surface judge deciding where objects may stand (names: povagent plugins).",
    ),
    judge_option: list[str] = typer.Option(
        [], "--judge-option", metavar="KEY=VALUE", help="An option for the judge's factory (repeatable)."
    ),
    plugin: list[str] = typer.Option(
        [], "--plugin", metavar="MODULE", help="Load a plugin module first: a dotted name or a .py path (repeatable)."
    ),
    cluster: str | None = typer.Option(
        None, "--cluster", metavar="local:N|tcp://HOST:PORT",
        help="Render the houses on a Dask cluster: N local worker processes, or a running scheduler "
        "(needs pip install 'povagent[cluster]'; the files do not depend on it).",
    ),
) -> None:
    """Generate a POVBench-format dataset of procedural houses.

    Builds the houses, renders their exploration frames and observer views, and writes the
    queries of all three conditions. Run again, it keeps the houses already complete in the
    folder and makes the missing ones (resume, or more houses with the same options).
    """
    from povagent.errors import PluginError
    from povagent.generate import generate_dataset

    options = judge_options(judge_option)
    try:
        report = generate_dataset(
            out,
            houses=houses,
            seed=seed,
            frames=frames,
            jobs=jobs,
            progress=sys.stdout.isatty(),
            with_render=with_render,
            judge=judge,
            judge_options=options,
            plugins=plugin,
            cluster=cluster,
            notice=lambda message: typer.echo(message, err=True),
        )
    except PluginError as exc:
        if ":" in judge and f"unknown judge {judge!r}" in str(exc):
            # The form the command took before judges were plugins: point at the plugin way.
            raise PluginError(
                f"{exc}\n--judge takes a registered name: register the judge with a register_judges hook "
                f"and load its module with --plugin {judge.partition(':')[0]}"
            ) from None
        raise
    shares = ", ".join(f"{d} {100 * s:.0f}%" for d, s in report.direction_shares().items())
    typer.echo(
        f"{out}: {len(report.houses)} houses ({report.kept} kept, {report.generated} made), {report.pairs} pairs, "
        f"{report.instances_per_condition} instances per condition ({shares} of pairs), "
        f"{report.renders} frames in {report.seconds:.1f} s"
    )
