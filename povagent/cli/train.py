"""The ``export-train`` command: a POVBench-format dataset -> a training set (Parquet or chat JSONL)."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from povagent.cli import app

#: Houses and pairs left out named on the console (all of them are in the card).
SHOWN_LEFT_OUT = 20


@app.command("export-train")
def export_train_command(
    dataset: Path = typer.Argument(..., metavar="DATASET", help="A POVBench-format dataset folder (generated, or the release's POVBench/)."),
    out: Path = typer.Option(..., "--out", metavar="FOLDER", help="Folder to write the training set to (new, empty, or an export to resume)."),
    fmt: str = typer.Option(
        "hf",
        "--format",
        metavar="hf|messages|openai",
        help="hf: Parquet shards with embedded images; messages: chat JSONL for TRL and LLaMA-Factory; openai: OpenAI fine-tuning JSONL (data URLs).",
    ),
    rationale: str = typer.Option(
        "s-cot", "--rationale", metavar="none|cot|s-cot", help="The reasoning before the answer, computed from the scene (none: the answer only)."
    ),
    split: str = typer.Option(
        "0.8,0.1,0.1", "--split", metavar="SHARES|RANGES", help="Split by house: shares 0.8,0.1,0.1 or index ranges train=0:800,test=800:1000."
    ),
    split_seed: int = typer.Option(0, "--split-seed", metavar="N", help="Seed of the house order the shares cut."),
    text_seed: int = typer.Option(0, "--text-seed", metavar="N", help="Seed of the rationales' wording (the facts never change)."),
    conditions: str = typer.Option("a,b,c", "--conditions", metavar="a,b,c", help="Conditions to export: a Inferred, b Stated, c Given."),
    max_shard_mb: int = typer.Option(500, "--max-shard-mb", min=1, metavar="MB", help="Largest shard, in MB."),
    task: str = typer.Option(
        "point",
        "--task",
        metavar="point|relation|multi-hop",
        help="What each example asks: the point task, or a generated task's multiple-choice question answered with its label.",
    ),
    exact: bool = typer.Option(False, "--exact-answers", help="Answer with the ground truth's exact float pixel instead of whole pixels."),
    exclude: list[Path] = typer.Option([], "--exclude", metavar="DATASET", help="An evaluation dataset whose houses must not be exported (repeatable)."),
    drop_excluded: bool = typer.Option(False, "--drop-excluded", help="Leave evaluation houses out (listed in the card) instead of stopping."),
    cluster: str = typer.Option(
        None, "--cluster", metavar="local:N|tcp://HOST:PORT", help="Write shards as Dask tasks (needs pip install 'povagent[cluster]')."
    ),
) -> None:
    """Export a training set, with rationales from the geometry.

    One example per instance and condition: the benchmark's question, then the answer.

    Resumable: the same command finishes a stopped export; other options over it are refused.
    """
    from povagent.train.export_options import ExportOptions
    from povagent.train.training_export import export_training_set

    options = ExportOptions(
        format=fmt,
        rationale=rationale,
        split=split,
        split_seed=split_seed,
        text_seed=text_seed,
        conditions=tuple(c.strip() for c in conditions.split(",") if c.strip()),
        max_shard_bytes=max_shard_mb * 1024 * 1024,
        exact_answers=exact,
        task=task,
    )

    def progress(shard: object, done: int, total: int) -> None:
        if sys.stderr.isatty():
            typer.echo(f"\r{done}/{total} shards", err=True, nl=False)

    report = export_training_set(dataset, out, options, exclude=exclude, drop_excluded=drop_excluded, cluster=cluster, progress=progress)
    if sys.stderr.isatty():
        typer.echo("", err=True)
    for where, why in list(report.left_out.items())[:SHOWN_LEFT_OUT]:
        typer.echo(f"left out {where}: {why}", err=True)
    if len(report.left_out) > SHOWN_LEFT_OUT:
        typer.echo(f"left out {len(report.left_out) - SHOWN_LEFT_OUT} more house(s)/pair(s): see {Path(out) / 'README.md'}", err=True)
    counts = ", ".join(f"{k} {v:,}" for k, v in report.counts.get("split", {}).items())
    skipped = f"; {len(report.skipped)} instance(s) left out (see README.md)" if report.skipped else ""
    dropped = f"; {len(report.left_out)} house(s)/pair(s) left out" if report.left_out else ""
    excluded = f"; {len(report.excluded)} evaluation house(s) excluded" if report.excluded else ""
    typer.echo(
        f"{out}: {report.examples:,} examples ({counts}) in {len(report.shards)} shard(s), "
        f"{report.shards_written} written now{skipped}{dropped}{excluded} ({report.seconds:.1f} s)"
    )
