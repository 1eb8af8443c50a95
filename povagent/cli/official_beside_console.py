"""The console table that keeps paper numbers in sight when a run was parsed leniently.

A lenient parser (``json``, ``rescale-1000`` ...) repairs answers the official runner leaves
unanswered or reads otherwise; its mean and response rate are not the paper's. Wherever the CLI
prints such a run's scores (after ``run``, ``rescore``, ``score`` on a run folder) this table
follows, putting the official parse's response rate and mean beside the repaired ones per slice,
both labelled. It reads the summary's ``official_parse`` section (see
:mod:`povagent.results.official_reading`); a lenient run without one (rows of format 0 without
readings: :mod:`povagent.results.upgrade`) gets a note saying how to obtain the official numbers. When the repair
changed no answer (every slice's mean and response rate are the official ones: a baseline's
answers, a model that wrote clean JSON) there is nothing to set beside and nothing is printed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from povagent.run.summary_model import Breakdown, Cell, OfficialParseBreakdown, RunSummary


def parser_reads_officially(name: str, options: dict[str, Any] | None = None, plugins: tuple[str, ...] = ()) -> bool:
    """Whether the parser ``name`` reads answers as the official runner does."""
    from povagent.plugins import get_plugin_host
    from povagent.results.official_reading import official_counterpart

    return official_counterpart(get_plugin_host(plugins).parser(name, options or {})) is None


def repair_changed_numbers(summary: Breakdown, official: OfficialParseBreakdown) -> bool:
    """Whether any slice's mean L2 or response rate differs between the repaired ``summary``
    and its ``official`` reading (an incomplete reading counts as a difference)."""
    from povagent.cli.slice_rows import breakdown_slices

    if official.rows_without_reading:
        return True
    mine = dict(breakdown_slices(summary))
    theirs = dict(breakdown_slices(official))
    return mine.keys() != theirs.keys() or any(
        (mine[name].mean_l2, mine[name].response_rate) != (theirs[name].mean_l2, theirs[name].response_rate) for name in mine
    )


def repair_changed(summary: RunSummary) -> bool:
    """Whether ``summary`` holds an official reading whose numbers differ from its own."""
    return summary.official_parse is not None and repair_changed_numbers(summary, summary.official_parse)


def render_official_beside(summary: RunSummary, parser: str, *, reads_officially: bool, run_dir: Any = None) -> None:
    """Print the official parse's response rate and mean beside the repaired ones (per slice), or
    the note saying how to get them; nothing when ``parser`` reads officially or its repairs
    changed no number."""
    from rich.console import Console

    from povagent.cli.console_width import fitted_table
    from povagent.cli.numbers import format_number
    from povagent.cli.slice_rows import breakdown_slices

    console = Console()
    if reads_officially:
        return
    official = summary.official_parse
    if official is None:
        where = run_dir if run_dir is not None else "RUN"
        console.print(
            f"[yellow]note:[/] parser {parser!r} repairs answers, so these numbers are not the paper's; "
            f"for the official reading run: povagent rescore {where} --parser official"
        )
        return
    if not repair_changed_numbers(summary, official):
        return

    def rate(cell: Cell | None) -> str:
        rr = cell.response_rate if cell is not None else None
        return "-" if rr is None else f"{100 * rr:.1f}%"

    lenient_cells = dict(breakdown_slices(summary))
    rows = []
    for name, cell in breakdown_slices(official):
        mine = lenient_cells.get(name)
        rows.append([name, format_number(mine.mean_l2 if mine is not None else None), rate(mine), format_number(cell.mean_l2), rate(cell)])
    headers = (f"L2 {parser} (repaired)", f"resp. {parser}", f"L2 {official.parser} (official)", f"resp. {official.parser}")
    console.print(
        fitted_table(
            [("slice", "label")] + [(h, "number") for h in headers],
            rows,
            title=f"Official parse beside {parser!r} (repaired): the official runner's reading is the one to compare with the paper",
            caption=(
                f"{official.rows_without_reading} row(s) with an answer carry no official reading and are left out: incomplete; "
                "run povagent rescore RUN --parser official"
                if official.rows_without_reading
                else None
            ),
        )
    )
