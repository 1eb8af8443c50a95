"""Commands on prompts and answers: ``show-prompt``, ``parse`` and ``rescore``.

``show-prompt`` shows exactly what a strategy sends for one instance (and saves its images,
markers drawn); ``parse`` reads one raw answer from stdin with a parser and prints the typed
result as JSON; ``rescore`` re-parses a finished run with another parser, offline.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import typer

from povagent.cli import app


@app.command("show-prompt")
def show_prompt_command(
    pipeline: Path = typer.Argument(..., help="Pipeline YAML (its dataset and strategy are used)."),
    instance: str = typer.Option(..., "--instance", help="Instance id house/pair/direction/condition."),
    out: Path | None = typer.Option(None, "--out", help="Folder for the images shown (default: ./show-prompt/<instance>)."),
) -> None:
    """Print the exact messages a strategy builds for one instance and save the images it shows."""
    from povagent.config.pipeline import load_pipeline
    from povagent.dataset.hub import resolve_hub_dataset
    from povagent.dataset.loader import load_dataset
    from povagent.errors import DatasetError, PluginError
    from povagent.exchange.images import ImageStore
    from povagent.exchange.preview import preview_request
    from povagent.plugins import did_you_mean, get_plugin_host

    config = resolve_hub_dataset(load_pipeline(pipeline))  # a dataset: {hub: ...} is fetched first
    dataset = load_dataset(config.dataset.root)
    inst = dataset.instance(instance)
    if inst is None:
        known = [i.id for i in dataset.instances()]
        raise DatasetError(f"no instance {instance!r} in {config.dataset.root}{did_you_mean(instance, known)}")
    host = get_plugin_host(config.plugins)
    strategy = host.create("strategy", config.strategy.name, config.strategy.options)
    images = ImageStore()
    try:
        request = strategy.build(inst, images)
    except (OSError, ValueError) as exc:
        raise PluginError(f"strategy {config.strategy.name!r} could not build a request for {instance}: {exc}") from exc
    out_dir = out if out is not None else Path("show-prompt") / re.sub(r"[^A-Za-z0-9_.-]+", "_", instance)
    preview = preview_request(request, images, inst, out_dir)
    typer.echo(preview.text)
    marked = sum(1 for s in preview.images if s.marked)
    typer.echo(f"--- {len(preview.images)} image(s) saved to {out_dir} ({marked} marked)", err=True)


@app.command("parse")
def parse_command(
    parser: str = typer.Option("official", "--parser", help="Parser name (see `povagent plugins`); default: the official runner's reading."),
    width: int = typer.Option(512, "--width", min=1, help="Frame width asked for, in pixels."),
    height: int = typer.Option(512, "--height", min=1, help="Frame height asked for, in pixels."),
    condition: str = typer.Option("a", "--condition", help="a (Inferred), b (Stated) or c (Given)."),
    frames: int = typer.Option(30, "--frames", min=1, help="Number of frames shown (A/B)."),
    plugin: list[str] = typer.Option([], "--plugin", help="Extra plugin module to load (repeatable)."),
) -> None:
    """Read one raw model answer on stdin and print its typed parse as JSON (pixels)."""
    from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema
    from povagent.dataset.models import Condition
    from povagent.errors import ConfigError
    from povagent.plugins import get_plugin_host

    names = {"inferred": "a", "stated": "b", "given": "c"}
    try:
        cond = Condition(names.get(condition.lower(), condition.lower()))
    except ValueError:
        raise ConfigError(f"--condition: {condition!r} is not one of a, b, c (inferred, stated, given)") from None
    if cond.uses_exploration_frames:
        spec = AnswerSpec(schema=frame_answer_schema(frames, width, height), width=width, height=height, n_frames=frames, asks_frame=True)
    else:
        spec = AnswerSpec(schema=point_answer_schema(width, height), width=width, height=height, n_frames=1, asks_frame=False)
    the_parser = get_plugin_host(tuple(plugin)).create("parser", parser, {})
    parsed = the_parser.parse(sys.stdin.read(), spec)
    out = {
        "status": str(parsed.status),
        "reason": parsed.reason,
        "selected_image": parsed.selected_image,
        "x": parsed.x,
        "y": parsed.y,
        "repair": parsed.repair,
        "points": [list(p) for p in parsed.points] if parsed.points else None,
        "span": parsed.span,
    }
    typer.echo(json.dumps(out, ensure_ascii=False))


@app.command("rescore")
def rescore_command(
    run_dir: Path = typer.Argument(..., help="A finished run folder (config.yaml + results.jsonl)."),
    parser: str = typer.Option("official", "--parser", help="Parser to re-read every raw answer with (default: official, paper-comparable)."),
    dataset: Path | None = typer.Option(None, "--dataset", help="Dataset folder (default: the run config's)."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Re-parse and re-score a finished run offline (no model call) into RUN_DIR/rescored-<parser>/.

    The default parser, ``official``, turns any run into paper-comparable numbers; with a
    lenient parser the official parse's numbers are printed beside the repaired ones.
    """
    from povagent.cli.dataset import render_summary
    from povagent.cli.official_beside import render_official_beside
    from povagent.run.rescore import rescore_run

    result = rescore_run(run_dir, parser, dataset_root=dataset)
    for w in result.warnings[:20]:
        typer.echo(f"warning: {w}", err=True)
    if as_json:
        typer.echo(json.dumps(result.summary, indent=2))
    else:
        render_summary(result.summary, title=f"{run_dir} re-parsed with {parser}")
        render_official_beside(result.summary, parser, reads_officially="official_parse" not in result.summary, run_dir=run_dir)
        typer.echo(f"parse status: {json.dumps(result.summary['parse_status'])}; repaired: {result.summary['repaired']}")
    typer.echo(f"written to {result.out_dir}", err=True)
