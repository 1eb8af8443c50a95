"""Commands on datasets and prediction files: ``validate`` and ``score``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Iterator

import typer

from povagent.cli import app


@app.command("validate")
def validate_command(
    dataset_dir: Path = typer.Argument(..., help="Dataset folder in the POVBench release layout."),
    width: int = typer.Option(512, help="Expected exploration frame width."),
    height: int = typer.Option(512, help="Expected exploration frame height."),
) -> None:
    """Check every file and image of a dataset; list every problem; exit 1 if any."""
    from povagent.dataset.validate import validate_dataset

    problems = validate_dataset(dataset_dir, (width, height))
    for p in problems:
        typer.echo(str(p))
    if problems:
        typer.echo(f"{len(problems)} problem(s) in {dataset_dir}", err=True)
        raise typer.Exit(1)
    typer.echo(f"{dataset_dir}: valid")


def breakdown_slices(breakdown: dict[str, Any]) -> Iterator[tuple[str, dict[str, Any]]]:
    """The rows of a breakdown table, labelled: overall, each condition, each direction."""
    from povagent.dataset.models import Condition

    yield "overall", breakdown["overall"]
    for c, cell in breakdown["per_condition"].items():
        yield f"{Condition(c).label} ({c.upper()})", cell
    yield from breakdown["per_direction"].items()


def render_summary(summary: dict[str, Any], title: str = "POVBench scores") -> None:
    """Print a summary (overall / per condition / per direction) as a rich table."""
    from rich.console import Console
    from rich.table import Table

    from povagent.scoring.predictions import format_number

    table = Table(title=title)
    for col in ("slice", "mean L2", "std", "resp. rate", "GT in frame", "strict L2", "n / total"):
        table.add_column(col, justify="right" if col != "slice" else "left")

    def add(name: str, cell: dict[str, Any]) -> None:
        rr = cell["response_rate"]
        pif = cell["pct_in_frame"]
        table.add_row(
            name,
            format_number(cell["mean_l2"]),
            format_number(cell["std_l2"]),
            "-" if rr is None else f"{100 * rr:.1f}%",
            "-" if pif is None else f"{pif:.1f}%",
            format_number(cell.get("mean_l2_strict")),
            f"{cell['n']} / {cell['n_total']}",
        )

    for name, cell in breakdown_slices(summary):
        add(name, cell)
    Console().print(table)


@app.command("score")
def score_command(
    predictions: Path = typer.Option(..., "--predictions", help="Official predictions (file, {metadata, predictions}, or folder) or our results.jsonl / run folder."),
    dataset: Path = typer.Option(..., "--dataset", help="Dataset folder in the release layout."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    strict: bool = typer.Option(False, "--strict", help="Stop at a bad house or pair of the dataset (default: report it, skip it, go on)."),
) -> None:
    """Score predictions with the official metric (mean L2 over answered, response rate beside it)."""
    from povagent.dataset.loader import load_dataset
    from povagent.scoring.predictions import score_predictions

    ds = load_dataset(dataset, strict=strict)
    for p in ds.problems:
        typer.echo(f"warning: dataset problem, skipped: {p}", err=True)
    summary, warnings = score_predictions(predictions, ds)
    for w in warnings[:20]:
        typer.echo(f"warning: {w}", err=True)
    if len(warnings) > 20:
        typer.echo(f"warning: ... and {len(warnings) - 20} more", err=True)
    if as_json:
        out = {k: summary[k] for k in ("overall", "per_condition", "per_direction", "per_condition_direction")}
        typer.echo(json.dumps(out, indent=2))
    else:
        render_summary(summary)
