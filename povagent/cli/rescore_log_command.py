"""``povagent rescore-log``: a second opinion on a run another harness made, from its log alone.

The scoring is :func:`povagent.run.rescore_log.rescore_log`; this prints it: the rules (who wrote
each, at which commit, which field of the log it read), their numbers side by side (overall and
per category, each with its 95% CI: a column per rule), and the questions the rules read
differently; or, with ``--json``, :class:`~povagent.run.rescore_log.RescoredLog`.
"""

from __future__ import annotations

import json
from pathlib import Path

import typer

from povagent.cli import app


def _cell(value: float | None, ci: tuple[float, float] | None) -> str:
    """``61.2% [55.0, 67.1]``; ``-`` where nothing was measured."""
    if value is None:
        return "-"
    return f"{100 * value:.1f}%" + (f" [{100 * ci[0]:.1f}, {100 * ci[1]:.1f}]" if ci is not None else "")


def _excerpt(reply: str, width: int = 40) -> str:
    """A reply on one line, ``⏎`` for each line break, cut to ``width`` characters."""
    flat = reply.replace("\r\n", "⏎").replace("\n", "⏎")
    return flat if len(flat) <= width else flat[: width - 1] + "…"


def render_rescored_log(result: object, shown: int) -> None:
    """Print the rules, their numbers and up to ``shown`` disagreements of a :class:`RescoredLog`."""
    from rich.console import Console

    from povagent.cli.console_width import fitted_tables
    from povagent.run.rescore_log import RescoredLog

    assert isinstance(result, RescoredLog)
    console = Console()
    read = "an answer (an option or a number)" if result.numerical else "an option"
    typer.echo(f"{result.file}: {result.items} replies of {result.set} logged by {result.harness}, read by {len(result.rules)} rules:")
    for r in result.rules:
        typer.echo(
            f"  {r.rule}{' (official)' if r.official else ''}: {r.harness}'s rule, {r.source}; reads {r.reads}; "
            f"scorer {r.scorer} ({r.metric}); reads {read} in {r.answered} of {result.items} replies"
        )
    categories = sorted({c for r in result.rules for c in r.per_category})
    rows = [["overall", *(_cell(r.overall, r.overall_ci) for r in result.rules)]]
    rows += [[c, *(_cell(r.per_category.get(c), r.per_category_ci.get(c)) for r in result.rules)] for c in categories]
    unread = "no answer read = 0" if result.numerical else "no option read = wrong"
    caption = f"Each rule's scorer's headline number over every logged question ({unread}), 95% bootstrap CI over questions."
    for table in fitted_tables([("slice", "label"), *((r.rule, "number") for r in result.rules)], rows, caption=caption):
        console.print(table)
    for note in result.notes:
        typer.echo(f"note: {note}")
    for r in result.rules:
        for line in r.unscorable[:shown]:
            typer.echo(f"unscorable: {line}", err=True)
        if r.unscorable:
            typer.echo(
                f"{len(r.unscorable)} repl{'y' if len(r.unscorable) == 1 else 'ies'} {r.rule} could not score (named above), left out of its figures", err=True
            )
    if result.stripped:
        typer.echo(
            f"{result.stripped} of {result.items} replies were changed by the harness's own filter before its rule read them "
            "(resps differs from filtered_resps): each rule above reads the field its 'reads' names."
        )
    if result.disagreements_total:
        names = [r.rule for r in result.rules]
        lines = [
            [d.item, _excerpt(d.reply), d.gold, *((d.labels[n] or "none") + (" ✓" if d.correct[n] else "") for n in names)]
            for d in result.disagreements[:shown]
        ]
        first = min(shown, len(result.disagreements))
        heading = f"The rules read {result.disagreements_total} of {result.items} replies differently (first {first}; ✓ a hit)"
        for table in fitted_tables([("item", "label"), ("reply", "label"), ("gold", "label"), *((n, "label") for n in names)], lines, title=heading):
            console.print(table)
    elif result.items:
        typer.echo(f"Every rule reads the same label in all {result.items} replies.")
    else:
        typer.echo("No record of the log could be scored (each is named below).")
    for problem in result.problems[:shown]:
        typer.echo(f"bad record: {problem}", err=True)
    if result.bad_records:
        typer.echo(f"{result.bad_records} record(s) left out (named above), {result.items} scored", err=True)


@app.command("rescore-log")
def rescore_log_command(
    file: Path = typer.Argument(
        ..., metavar="FILE", help="lmms-eval's --log_samples file (<date>_samples_<task>.jsonl) or VLMEvalKit's prediction file (.xlsx or .tsv)."
    ),
    harness: str = typer.Option(..., "--harness", metavar="NAME", help="The harness that wrote FILE: lmms-eval or vlmevalkit."),
    set_name: str = typer.Option(
        ...,
        "--set",
        metavar="NAME",
        help="The set the log is of: the key of a registered dataset format whose answers are choices or numbers (povagent plugins lists the formats).",
    ),
    as_json: bool = typer.Option(
        False, "--json", help="Print {set, items, rules: [{rule, source, overall, per_category, ...}], ...} as JSON instead of tables."
    ),
    shown: int = typer.Option(20, "--show", min=0, metavar="N", help="How many disagreements and bad records to print (the JSON holds them all)."),
    plugin: list[str] = typer.Option(
        [], "--plugin", metavar="MODULE", help="Load a plugin module first (a set's or a rule's): a dotted name or a .py path (repeatable)."
    ),
) -> None:
    """Score another harness's log by every rule of its set, offline.

    No model and no media: only FILE is read. Each reply is read by the set's own rule and by each
    rule povagent reproduces for the set (lmms-eval's, VLMEvalKit's), each at the commit it names;
    a bad record is named in one line and the rest are still scored.
    """
    from povagent.plugins import get_plugin_host
    from povagent.run.rescore_log import rescore_log

    result = rescore_log(file, harness, set_name, host=get_plugin_host(tuple(plugin)))
    if as_json:
        typer.echo(json.dumps(result.model_dump(mode="json"), indent=2))
        return
    render_rescored_log(result, shown)
