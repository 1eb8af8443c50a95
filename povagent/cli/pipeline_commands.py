"""Commands that run pipelines: ``run``, ``sweep`` and ``plugins``.

Thin wrappers: each reads its YAML with :mod:`povagent.config.pipeline`, calls :mod:`povagent.run.runner` or
:mod:`povagent.run.sweep`, and prints a short rich table.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from povagent.cli import app
from povagent.cli.console_width import PathTitle
from povagent.cli.options import keep_errors_option, strict_option, trust_remote_code_option
from povagent.results.summary_json import finite_json

if TYPE_CHECKING:
    from povagent.run.summary_model import RunSummary, SuccessBreakdown


def _summary_table(summary: RunSummary, title: PathTitle, run_dir: Path) -> None:
    """The run's score tables under ``title`` (the run folder and what ran)."""
    from povagent.cli.dataset_commands import render_summary
    from povagent.cli.diagnostics_table import render_diagnostics
    from povagent.cli.metrics_table import protocol_scorers, render_metrics

    shown = []  # scorers whose numbers a table of their own printed
    success = _success_summary(summary, run_dir)
    if success is not None:  # a real-world set: success rates, as the paper reports them
        _success_table(success, title)
        shown += protocol_scorers(summary, "marked_hit")
    if _scored_officially(summary):
        render_summary(summary, title=title)
        shown += protocol_scorers(summary, "normalized_l2")
    render_metrics(summary, title, shown)  # every other scorer's declared metrics
    render_diagnostics(summary)  # additions, under the official table


def _success_summary(summary: RunSummary, run_dir: Path) -> SuccessBreakdown | None:
    """A real-world run's success breakdown with response rates (``None`` for other runs).

    Read from the run's rows as ``povagent report`` reads them, because the official columns
    of ``summary.json`` say nothing about a set without official ground truth; the runner's
    own breakdown is kept when the folder holds rows of keys outside this run's selection.
    """
    if summary.success is None:
        return None
    from povagent.report.collect import run_success_breakdown
    from povagent.run.summary_model import SuccessBreakdown

    full = run_success_breakdown(run_dir)
    if full is None:
        return summary.success
    read = SuccessBreakdown.model_validate(full)
    return read if read.overall.n_total == summary.success.overall.n_total else summary.success


def _scored_officially(summary: RunSummary) -> bool:
    """Did a scorer of the run follow POVBench's ``normalized_l2`` protocol (a summary without the
    pipeline: its default scorers did)?"""
    from povagent.cli.metrics_table import protocol_scorers

    return bool(protocol_scorers(summary, "normalized_l2"))


def _what_ran(summary: RunSummary, backend: str) -> str:
    """The backend and the model that answered, from ``summary.json``: ``litellm gpt-5.4 =
    openai/gpt-5.4``; a baseline is its own model (``center``)."""
    from povagent.results.rows import model_label

    pipeline = summary.pipeline
    model = model_label(pipeline.model, pipeline.profile) if pipeline is not None else ""
    return backend if model in ("", backend) else f"{backend} {model}"


def _cell_title(name: str, summary: RunSummary, backend: str) -> str:
    """A sweep cell's name with the model that answered (left out when the name is it)."""
    what = _what_ran(summary, backend)
    return f"[bold]{name}[/]" if what == name else f"[bold]{name}[/] ({what})"


def _success_table(success: SuccessBreakdown, title: PathTitle) -> None:
    from rich.console import Console

    from povagent.cli.console_width import fitted_table
    from povagent.cli.slice_rows import breakdown_slices
    from povagent.report.sweep_table import percent, rate

    rows = []
    for name, cell in breakdown_slices(success):
        answered = "-" if cell.n_answered is None else f"{cell.n_answered} / {cell.n_total}"
        rows.append([name, rate(cell), f"{cell.n_success} / {cell.n_total}", percent(cell.response_rate), answered])
    columns = [("slice", "label")] + [(h, "number") for h in ("success rate", "hits / total", "resp. rate", "answered / total")]
    Console().print(fitted_table(columns, rows, title=title._replace(after=f"{title.after}\nsuccess rate (unanswered = failure)")))


@app.command("run")
def run_command(
    pipeline: Path = typer.Argument(
        ...,
        metavar="PIPELINE",
        help="The pipeline YAML file: dataset, model backend, strategy, parser, scorers and run folder "
        "(a pipeline explained: docs/tutorials/first-evaluation.md; every key: the YAML reference, see docs/reference/index.md).",
    ),
    output: Path | None = typer.Option(
        None, "--output", "-o", metavar="FOLDER", help="Run folder to write to, instead of the YAML's output: key."
    ),
    limit: int | None = typer.Option(None, "--limit", min=1, metavar="N", help="Run only the first N instances."),
    keep_errors: bool = keep_errors_option(),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Do not show the progress bar."),
    as_json: bool = typer.Option(False, "--json", help="Print the run summary as JSON instead of tables."),
    strict: bool = strict_option(),
    trust_remote_code: bool = trust_remote_code_option(),
) -> None:
    """Run one pipeline and print its scores.

    A run resumes from its run folder: only the keys without a row are sent to the model.
    Exit code 0: every key answered or unparseable; 3: some keys failed; 4: stopped early;
    130: interrupted (Ctrl-C); 143: terminated (SIGTERM), stopped as cleanly as Ctrl-C.
    """
    from povagent.config.pipeline import load_pipeline
    from povagent.run.progress import make_progress
    from povagent.run.runner import run_pipeline
    from povagent.run.stop_signals import sigterm_as_interrupt

    overrides: dict[str, Any] = {}
    if output is not None:
        overrides["output"] = str(output)
    if limit is not None:
        overrides["instances"] = {"limit": limit}
    config = load_pipeline(pipeline, overrides=overrides)
    if strict:
        config = config.model_copy(update={"dataset": config.dataset.model_copy(update={"strict": True})})
    try:
        with sigterm_as_interrupt() as stop:  # a scheduler's SIGTERM stops as cleanly as Ctrl-C
            result = run_pipeline(
                config, progress=make_progress(str(config.output), quiet=quiet or as_json), console_log=True,
                retry_failed=not keep_errors, trust_remote_code=trust_remote_code,
            )
    except KeyboardInterrupt:
        typer.echo(
            f"{stop.what}: rows written so far are kept in {config.output} (summary.json says interrupted); "
            f"run `{_again(pipeline, trust_remote_code)}` again to resume",
            err=True,
        )
        raise typer.Exit(stop.exit_code) from None
    from povagent.cli.process_exit import allow_fast_exit

    allow_fast_exit()  # the run folder is complete and closed (see povagent.cli.process_exit)
    if as_json:
        typer.echo(json.dumps(finite_json(result.summary.model_dump(mode="json", exclude_unset=True)), indent=2))
        raise typer.Exit(result.exit_code)
    from povagent.run.runner import SET_UP_KINDS

    if result.stop_kind in SET_UP_KINDS:  # nothing was sent: no table to show, the one line says it all
        typer.echo(f"stopped early: {result.stopped}", err=True)
        raise typer.Exit(result.exit_code)
    summary = result.summary
    # load_pipeline resolved backend and parser
    ran = f" ({_what_ran(result.summary, config.backend.name)} / {config.strategy.name} / {config.parser.name})"  # type: ignore[union-attr]
    title = PathTitle(config.output, ran)
    _summary_table(summary, title, result.run_dir)
    if summary.nan_coordinate_rows:
        from povagent.results.official_reading import nan_warning

        typer.echo(f"warning: {nan_warning(summary.nan_coordinate_rows)}", err=True)
    if _scored_officially(summary):
        from povagent.cli.official_beside_console import parser_reads_officially, render_official_beside

        render_official_beside(
            summary,
            config.parser.name,  # type: ignore[union-attr]  # load_pipeline resolved it
            # load_pipeline resolved the parser
            reads_officially=parser_reads_officially(config.parser.name, config.parser.options, tuple(config.plugins)),  # type: ignore[union-attr]
            run_dir=result.run_dir,
        )
    # two short lines rather than one that an 80-column terminal breaks mid-phrase
    rows = summary.rows
    if rows is not None:
        typer.echo(
            f"{rows.done}/{rows.total} keys: {rows.answered} answered, {rows.parse_error} parse errors, "
            f"{rows.infra_error} infra errors"
        )
    typer.echo(
        f"this session: {result.stats.requests} requests, {result.stats.cache_hits} cache hits, "
        f"{result.stats.retries} retries, {result.stats.wall_s:.1f} s"
    )
    _say_what_next(result, _again(pipeline, trust_remote_code))
    raise typer.Exit(result.exit_code)


def _again(pipeline: Path, trust_remote_code: bool) -> str:
    """The command that resumes a run (with the flag it was given: the grant is not stored)."""
    return f"povagent run {pipeline}" + (" --trust-remote-code" if trust_remote_code else "")


def _say_what_next(result: Any, command: str) -> None:
    """After a run that left keys without an answer: how many, why, and what to run next."""
    if result.stopped is not None:
        typer.echo(f"stopped early: {result.stopped}", err=True)
    failed, missing = result.n_failed, result.n_missing
    if failed or missing:
        parts = [f"{failed} key(s) failed (infra_error)"] if failed else []
        if missing:
            parts.append(f"{missing} key(s) not tried")
        typer.echo(
            f"{', '.join(parts)}: see {result.run_dir / 'log.jsonl'}; fix the cause, then run `{command}` again "
            "(failed keys are tried again, answered ones are kept)",
            err=True,
        )


@app.command("sweep")
def sweep_command(
    sweep: Path = typer.Argument(
        ...,
        metavar="SWEEP",
        help="The sweep YAML file: a base pipeline, the axes to vary (models, strategies, conditions...) "
        "and named overrides.",
    ),
    dry_run: bool = typer.Option(
        False, "--dry-run", help="Only print the cells, the requests still to make and a token estimate (per turn for a multi-turn strategy); call no model."
    ),
    keep_errors: bool = keep_errors_option(),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Do not show the progress bars."),
    strict: bool = strict_option(),
    cluster: str | None = typer.Option(
        None, "--cluster", metavar="local:N|tcp://HOST:PORT",
        help="Run each cell as a task on Dask: local:N starts N worker processes here, tcp://HOST:PORT "
        "uses a running scheduler (overrides the YAML's cluster: key; needs pip install 'povagent[cluster]').",
    ),
    trust_remote_code: bool = trust_remote_code_option(),
) -> None:
    """Run every cell of a sweep: a grid of pipelines.

    Each cell gets its own run folder, sweep.json lists them, and all cells share one response
    cache, so running the same sweep again makes no new model calls.
    """
    from rich.console import Console

    from povagent.cli.console_width import fitted_table
    from povagent.cli.official_beside_console import repair_changed
    from povagent.report.sweep_table import dry_run_table, mean_l2, percent, rate, sweep_table
    from povagent.run.stop_signals import sigterm_as_interrupt
    from povagent.run.sweep import expand_sweep, run_sweep
    from povagent.run.sweep_estimate import dry_run as plan

    console = Console()
    if dry_run:
        sweep_cfg, cells = expand_sweep(sweep, strict=strict)
        columns, rows, notes = dry_run_table(plan(cells))
        console.print(fitted_table(columns, rows, title=PathTitle(sweep_cfg.output, f" ({len(cells)} cells)", before=f"dry run of {sweep.name}: ")))
        for note in notes:  # a turn taken only sometimes is counted for every key: an upper bound
            console.print(f"* {note}", markup=False, highlight=False)
        return

    def done(cell: Any, res: Any) -> None:
        summary: RunSummary = res.summary
        success = _success_summary(summary, res.run_dir)
        if success is not None:  # a real-world set: no official error to show
            o = success.overall
            console.print(
                f"{_cell_title(cell.name, summary, cell.config.backend.name)}: success rate {rate(o)}, "
                f"response rate {percent(o.response_rate)}, {res.stats.requests} requests, {res.stats.cache_hits} cache hits",
                highlight=False,
            )
            return
        official = summary.official_parse
        beside = "" if official is None or not repair_changed(summary) else (
            f" (repaired by {summary.pipeline.parser if summary.pipeline is not None else 'a lenient parser'}; official parse: "
            f"mean L2 {mean_l2(official.overall)}, response rate {percent(official.overall.response_rate)})"
        )
        console.print(
            f"{_cell_title(cell.name, summary, cell.config.backend.name)}: mean L2 {mean_l2(summary.overall)}, "
            f"response rate {percent(summary.overall.response_rate)}{beside}, {res.stats.requests} requests, "
            f"{res.stats.cache_hits} cache hits",
            highlight=False,
        )

    if cluster is not None:
        from povagent.config.cluster_spec import parse_cluster_spec

        parse_cluster_spec(cluster)  # a malformed value is refused before anything starts
    try:
        with sigterm_as_interrupt() as stop:  # a scheduler's SIGTERM stops as cleanly as Ctrl-C
            result = run_sweep(sweep, quiet=quiet, retry_failed=not keep_errors, strict=strict, on_cell_done=done,
                               cluster=cluster, notify=lambda message: typer.echo(message, err=True),
                               trust_remote_code=trust_remote_code)
    except KeyboardInterrupt:
        command = f"povagent sweep {sweep}" + (f" --cluster {cluster}" if cluster else "") + (" --trust-remote-code" if trust_remote_code else "")
        typer.echo(f"{stop.what}: finished rows are kept; run `{command}` again to resume", err=True)
        raise typer.Exit(stop.exit_code) from None
    command = f"povagent sweep {sweep}" + (f" --cluster {cluster}" if cluster else "") + (" --trust-remote-code" if trust_remote_code else "")
    for name, error in result.failed.items():
        typer.echo(f"cell {name} failed: {error}", err=True)
    if result.failed:
        typer.echo(
            f"{len(result.failed)} cell(s) failed ({', '.join(result.failed)}): the rows they wrote are kept; fix the cause, "
            f"then run `{command}` again to resume them",
            err=True,
        )
    finished = [c for c in result.cells if c.name in result.results]
    summaries = {c.name: result.results[c.name].summary for c in finished}
    successes = {c.name: _success_summary(result.results[c.name].summary, result.results[c.name].run_dir) for c in finished}
    columns, rows = sweep_table(summaries, successes, repair_changed)
    title = PathTitle(result.output / "sweep.json", before=f"sweep {sweep.name} ({len(result.cells)} cells) -> ")
    console.print(fitted_table(columns, rows, title=title))
    from povagent.cli.process_exit import allow_fast_exit
    from povagent.run.run_result import EXIT_STOPPED

    allow_fast_exit()  # every cell's folder is complete and closed (see povagent.cli.process_exit)
    codes = [result.results[c.name].exit_code for c in finished] + [EXIT_STOPPED] * len(result.failed)
    for cell in finished:
        res = result.results[cell.name]
        if res.exit_code:
            typer.echo(f"cell {cell.name}:", err=True)
            _say_what_next(res, command)
    raise typer.Exit(max(codes, default=0))


#: The heading of each kind in ``povagent plugins``.
KIND_HEADINGS = {"profile": "model profiles", "strategy": "strategies", "tool": "active-mode tools", "answer_type": "answer types", "format": "dataset formats"}


def _plugins_table(entries: dict[str, list[Any]], width: int) -> Any:
    """The plugins, a section per kind: name, then description with "from <source>" under it.

    Three columns (kind, name, source) beside a description leave it a dozen characters in
    80 columns; here the description gets all but the name's width, and a source too long for
    it (a distribution's entry point, a deep .py path) goes on over several lines, whole,
    broken between words.
    """
    from rich.table import Table
    from rich.text import Text

    from povagent.cli.console_width import break_between_words

    name_width = max((len(e.name) for es in entries.values() for e in es), default=4)
    name_width = min(name_width, max(12, width * 3 // 8))  # 30 in 80 columns: the longest built-in name whole
    room = max(20, width - name_width - 7)  # borders and padding of a two-column table
    table = Table(title="povagent plugins", show_header=False)
    table.add_column("name", overflow="fold", width=name_width)
    table.add_column("description", overflow="fold")
    for i, (kind, kind_entries) in enumerate(entries.items()):
        if i:
            table.add_section()
        table.add_row(Text(KIND_HEADINGS.get(kind, f"{kind}s"), style="bold"), "")
        for e in kind_entries:
            text = Text(e.description or "(no description)")
            text.append("\n" + break_between_words("from " + e.source, room), style="dim")
            table.add_row(Text(e.name), text)
    return table


def _profile_fields(entry: Any) -> dict[str, Any]:
    """A model profile's litellm model and default parser, a dataset format's answer type,
    official rule, upstream source and licence (for ``plugins --json``); nothing for other kinds, or for
    a plugin's object without those fields."""
    if entry.kind == "format":  # its source (repo@commit) is "upstream": "source" is the plugin's
        names = {
            "answer_type": "answer_type",
            "official_parser": "official_parser",
            "official_scorer": "official_scorer",
            "upstream": "source",
            "licence": "licence",
        }
        return {k: getattr(entry.factory, a) for k, a in names.items() if isinstance(getattr(entry.factory, a, None), str)}
    if entry.kind != "profile":
        return {}
    fields = {"model": getattr(entry.factory, "litellm_model", None), "parser": getattr(entry.factory, "default_parser", None)}
    return {k: v for k, v in fields.items() if isinstance(v, str)}


@app.command("plugins")
def plugins_command(as_json: bool = typer.Option(False, "--json", help="Print the list as JSON instead of a table.")) -> None:
    """List every plugin a YAML file can name, and its source.

    Every backend, strategy, parser, scorer, surface judge, model profile, active-mode tool, answer type and dataset format, with the package
    or file that registered it; plugins that failed to load are listed after them (exit code 1).
    """
    from rich.console import Console

    from povagent.plugins import KINDS, build_plugin_host

    host = build_plugin_host(strict=False)
    listed = {**{k: host.entries(k) for k in (*KINDS, "profile")}, "tool": host.tool_entries(), **{k: host.entries(k) for k in ("answer_type", "format")}}
    if as_json:
        out: dict[str, list[dict[str, Any]]] = {
            k: [{"name": e.name, "source": e.source, "description": e.description, **_profile_fields(e)} for e in entries]
            for k, entries in listed.items()
        }
        out["failures"] = [{"plugin": f.plugin, "origin": f.origin, "error": f.error} for f in host.failures]
        typer.echo(json.dumps(out, indent=2))
    else:
        console = Console()
        console.print(_plugins_table(listed, console.width))
        for f in host.failures:
            console.print(f"[red]failed:[/] {f}", highlight=False)
    if host.failures:
        sys.exit(1)
