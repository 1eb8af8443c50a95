"""Commands on prompts and answers: ``show-prompt``, ``parse`` and ``rescore``.

``show-prompt`` shows exactly what a strategy sends for one instance, every planned turn (and
saves its images, markers drawn); ``parse`` reads one raw answer from stdin with a parser and prints the typed
result as JSON; ``rescore`` re-parses a finished run with another parser, offline.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

import typer

from povagent.cli import app

#: How an instance id is written, and one as `povagent generate` names them, for the help (an
#: error message shows an id of the dataset at hand instead: pair ids differ between sets).
INSTANCE_ID_FORMAT = "HOUSE/PAIR/DIRECTION/CONDITION"
INSTANCE_ID_EXAMPLE = "train_house_00000/pair_000/right/a"


def unknown_instance_message(instance: str, known: list[str], where: object) -> str:
    """Why ``instance`` names no instance of the dataset at ``where``, how ids are written,
    a near id if one is close, and a few real ids to copy (from the same house when it exists)."""
    from povagent.dataset.release_models import Condition, Direction
    from povagent.plugins import did_you_mean

    lines = [f"no instance {instance!r} in {where}{did_you_mean(instance, known)}"]
    parts = instance.split("/")
    houses = {k.split("/")[0] for k in known}
    directions = [str(d) for d in Direction]
    conditions = [str(c) for c in Condition]
    if len(parts) != 4:
        lines.append(f"an instance id has four parts separated by '/' (this one has {len(parts)})")
    elif parts[0] not in houses:
        lines.append(f"no house {parts[0]!r} in the dataset ({len(houses)} houses)")
    elif parts[2] not in directions:
        lines.append(f"direction {parts[2]!r} is not one of {', '.join(directions)}")
    elif parts[3] not in conditions:
        lines.append(f"condition {parts[3]!r} is not one of a (Inferred), b (Stated), c (Given)")
    else:
        lines.append(f"house {parts[0]!r} has no pair {parts[1]!r} with direction {parts[2]!r} and condition {parts[3]!r}")
    same_house = [k for k in known if k.split("/")[0] == parts[0]]
    example = (same_house or known or [INSTANCE_ID_EXAMPLE])[0]  # a real id: never the one mistyped
    lines.append(f"an instance id is {INSTANCE_ID_FORMAT}, e.g. {example}")
    examples = _spread(same_house or known, 3)
    if examples:
        lines.append("ids in this dataset" + (f" for house {parts[0]}" if same_house else "") + ":")
        lines.extend(f"  {k}" for k in examples)
    return "\n".join(lines)


def _spread(ids: list[str], n: int) -> list[str]:
    """Up to ``n`` of ``ids``, each from another house and pair where there are enough."""
    picked: list[str] = []
    seen: set[tuple[str, ...]] = set()
    for k in ids:
        house_pair = tuple(k.split("/")[:2])
        if house_pair not in seen:
            seen.add(house_pair)
            picked.append(k)
    picked += [k for k in ids if k not in picked]
    return picked[:n]


@app.command("show-prompt")
def show_prompt_command(
    pipeline: Path = typer.Argument(..., metavar="PIPELINE", help="The pipeline YAML file whose dataset and strategy are used."),
    instance: str = typer.Option(
        ...,
        "--instance",
        metavar="ID",
        help=f"The instance to show, as {INSTANCE_ID_FORMAT}, e.g. {INSTANCE_ID_EXAMPLE} "
        "(PAIR as the house file's pair_id; condition a: Inferred, b: Stated, c: Given).",
    ),
    out: Path | None = typer.Option(
        None, "--out", metavar="FOLDER", help="Folder to save the images in (default: ./show-prompt/ID, slashes as _)."
    ),
) -> None:
    """Print every turn a strategy sends for one instance, exactly.

    The text, the image labels and the generation settings are printed as the model receives
    them; the images (markers drawn) are saved to a folder. A multi-turn strategy's later turns
    show <<the model's answer to turn N>> where its earlier answer will stand.
    """
    from povagent.config.pipeline import load_pipeline, resolve_hub_dataset
    from povagent.dataset.evaluation_set import open_evaluation_set
    from povagent.errors import DatasetError, PluginError
    from povagent.exchange.images import ImageStore
    from povagent.exchange.preview import preview_request
    from povagent.interfaces import declares_turns
    from povagent.plugins import get_plugin_host
    from povagent.run.pending import asked_by

    config = resolve_hub_dataset(load_pipeline(pipeline))  # a dataset: {hub: ...} is fetched first
    dataset = asked_by(
        config,
        open_evaluation_set(
            config.dataset.root, format=config.dataset.format, images=config.dataset.images, options=config.dataset.options, plugins=config.plugins
        ),
    )
    inst = dataset.instance(instance)
    if inst is None:
        # an instance of a house the loader left out: say why in one line, not "no such id"
        house = instance.split("/", 1)[0]
        left_out = house not in dataset.houses
        why = next((p for p in dataset.problems if left_out and Path(p.file).parts[:2] == ("artifacts", house)), None)
        if why is not None:
            raise DatasetError(f"no instance {instance!r} in {config.dataset.root}: loading left it out ({why})")
        raise DatasetError(unknown_instance_message(instance, [i.id for i in dataset.instances()], config.dataset.root))
    host = get_plugin_host(config.plugins)
    strategy = host.strategy(config.strategy.name, config.strategy.options)
    images = ImageStore()
    try:
        turns = strategy.plan_turns(inst, images)
    except (OSError, ValueError) as exc:
        raise PluginError(f"strategy {config.strategy.name!r} could not build a request for {instance}: {exc}") from exc
    out_dir = out if out is not None else Path("show-prompt") / re.sub(r"[^A-Za-z0-9_.-]+", "_", instance)
    saved: list[Any] = []
    for number, turn in enumerate(turns, start=1):
        if len(turns) > 1:
            typer.echo(turn_heading(number, len(turns), turn))
        # one turn: its images as before; several: each turn's in its own folder
        preview = preview_request(turn.request, images, inst, out_dir if len(turns) == 1 else out_dir / f"turn-{number}")
        typer.echo(preview.text)
        saved += preview.images
    if not declares_turns(strategy):
        typer.echo(
            f"note: strategy {config.strategy.name!r} overrides solve() without plan_turns(): "
            "turns after the first are not known before it runs",
            err=True,
        )
    marked = sum(1 for s in saved if s.marked)
    typer.echo(f"--- {len(saved)} image(s) saved to {out_dir} ({marked} marked)", err=True)


def turn_heading(number: int, total: int, turn: Any) -> str:
    """The line ``show-prompt`` prints above each turn of a multi-turn strategy."""
    what = "" if turn.sent else ", worked out by the strategy, not sent"
    return f"=== turn {number} of {total}{what}" + (f" ({turn.note})" if turn.note else "") + " ==="


@app.command("parse")
def parse_command(
    parser: str = typer.Option(
        "official", "--parser", metavar="NAME", help="Parser to read the answer with (names: povagent plugins); "
        "official reads it as the authors' runner does."
    ),
    width: int = typer.Option(512, "--width", min=1, metavar="PIXELS", help="Width of the frame the question was about."),
    height: int = typer.Option(512, "--height", min=1, metavar="PIXELS", help="Height of the frame the question was about."),
    condition: str = typer.Option(
        "a", "--condition", metavar="CONDITION", help="a (Inferred), b (Stated) or c (Given), or those names: A and B answers name a frame."
    ),
    frames: int = typer.Option(30, "--frames", min=1, metavar="N", help="Number of exploration frames shown (conditions a and b)."),
    choices: str | None = typer.Option(
        None, "--choices", metavar="LABEL=TEXT,...", help="Read a multiple-choice answer among these options "
        "(A=right,B=left,C=front,D=back); the JSON's choice is the label read, or null."
    ),
    plugin: list[str] = typer.Option(
        [], "--plugin", metavar="MODULE", help="Load a plugin module first: a dotted name or a .py path (repeatable)."
    ),
) -> None:
    """Parse one raw model answer (read from stdin) into JSON.

    The JSON holds the parse status, the frame chosen and the point in pixels (or, with
    --choices, the option label chosen), and says whether the parser had to repair the answer.
    """
    from povagent.answers.spec import AnswerSpec, choice_answer_schema, frame_answer_schema, point_answer_schema
    from povagent.dataset.release_models import Condition
    from povagent.errors import ConfigError
    from povagent.plugins import get_plugin_host

    names = {"inferred": "a", "stated": "b", "given": "c"}
    try:
        cond = Condition(names.get(condition.lower(), condition.lower()))
    except ValueError:
        raise ConfigError(f"--condition: {condition!r} is not one of a, b, c (inferred, stated, given)") from None
    if choices is not None:
        options = options_from_flag(choices)
        labels = tuple(label for label, _ in options)
        spec = AnswerSpec(schema=choice_answer_schema(labels), width=width, height=height, asks_frame=False, choices=options)
    elif cond.uses_exploration_frames:
        spec = AnswerSpec(schema=frame_answer_schema(frames, width, height), width=width, height=height, n_frames=frames, asks_frame=True)
    else:
        spec = AnswerSpec(schema=point_answer_schema(width, height), width=width, height=height, n_frames=1, asks_frame=False)
    from povagent.results.plugin_errors import MAX_REPLY_CHARS, parse_or_unparseable

    the_parser = get_plugin_host(tuple(plugin)).parser(parser, {})
    # read as a run reads it: a reply past the bound is a non-response, never read whole
    parsed = parse_or_unparseable(the_parser, sys.stdin.read(MAX_REPLY_CHARS + 1), spec)
    out = {
        "status": str(parsed.status),
        "reason": parsed.reason,
        "selected_image": parsed.selected_image,
        "x": parsed.x,
        "y": parsed.y,
        "repair": parsed.repair,
        "points": [list(p) for p in parsed.points] if parsed.points else None,
        "span": parsed.span,
        "choice": parsed.choice,
    }
    typer.echo(json.dumps(out, ensure_ascii=False))


def options_from_flag(value: str) -> tuple[tuple[str, str], ...]:
    """The ``(label, text)`` options of ``--choices A=right,B=left``; a malformed list is one
    ``ConfigError`` line naming the option."""
    from povagent.errors import ConfigError

    options: list[tuple[str, str]] = []
    for item in value.split(","):
        label, sep, text = item.partition("=")
        label, text = label.strip(), text.strip()
        if not sep or not label or not text:
            raise ConfigError(f"--choices: {item.strip()!r} is not LABEL=TEXT (write --choices \"A=right,B=left\")")
        if any(label == seen for seen, _ in options):
            raise ConfigError(f"--choices: the label {label!r} appears twice")
        options.append((label, text))
    return tuple(options)


@app.command("rescore")
def rescore_command(
    run_dir: Path = typer.Argument(..., metavar="RUN_DIR", help="A finished run folder (with config.yaml and results.jsonl)."),
    parser: str | None = typer.Option(
        None, "--parser", metavar="NAME", help="Parser to read every raw answer again with (names: povagent plugins). "
        "Default: the official reading, comparable with the paper (official, or the run's own parser when it reads "
        "as the official runner does, such as active)."
    ),
    dataset: Path | None = typer.Option(
        None, "--dataset", metavar="FOLDER", help="Dataset folder, if not the one named in the run's config.yaml."
    ),
    scorer: list[str] = typer.Option(
        [], "--scorer", metavar="NAME", help="A scorer to add to the run's own (repeatable), e.g. --scorer diagnose "
        "--scorer relation: their figures go to summary.json's diagnostics, beside the official ones."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON instead of tables."),
    plugin: list[str] = typer.Option(
        [], "--plugin", metavar="MODULE", help="Load a plugin module first: a dotted name or a .py path (repeatable). "
        "The plugins a run folder's config.yaml names are never imported: pass the ones the run needs here."
    ),
) -> None:
    """Score a finished run again with another parser, offline.

    No model is called: the raw answers in the run folder are read again and the result is
    written to RUN_DIR/rescored-PARSER/. The default, the official reading (official, or the
    run's own parser when it reads as the official runner does), turns any run into numbers
    comparable with the paper; with a lenient parser the official parse's numbers are
    printed beside the repaired ones.
    """
    from povagent.cli.console_width import PathTitle
    from povagent.cli.dataset_commands import render_summary
    from povagent.cli.diagnostics_table import render_diagnostics
    from povagent.cli.metrics_table import protocol_scorers, render_metrics
    from povagent.cli.official_beside_console import render_official_beside
    from povagent.run.rescore import rescore_run

    result = rescore_run(run_dir, parser, dataset_root=dataset, plugins=plugin, extra_scorers=tuple(scorer))
    summary = result.summary
    parser = str(summary.parser)
    for w in result.warnings[:20]:
        typer.echo(f"warning: {w}", err=True)
    if as_json:
        from povagent.results.summary_json import finite_json

        typer.echo(json.dumps(finite_json(summary.model_dump(mode="json", exclude_unset=True)), indent=2))
    else:
        title = PathTitle(run_dir, f" re-parsed with {parser}")
        official = protocol_scorers(summary, "normalized_l2")
        if official:  # POVBench's error table, for rows a normalized_l2 scorer scored
            render_summary(summary, title=title)
        render_metrics(summary, title, shown=official)  # every other scorer's declared metrics
        render_official_beside(summary, parser, reads_officially=summary.official_parse is None, run_dir=run_dir)
        render_diagnostics(summary)
        typer.echo(f"parse status: {json.dumps(summary.parse_status)}; repaired: {summary.repaired}")
    typer.echo(f"written to {result.out_dir}", err=True)
