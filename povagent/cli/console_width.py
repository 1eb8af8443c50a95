"""Keeping the CLI's tables readable in a narrow terminal (80 columns and less).

Rich fits a table to the console by shrinking its widest columns and, when a word is still
too long, cutting its end off with an ellipsis. That is right for descriptions and wrong for
what a user scans a table for: a label (a slice, a sweep cell) cut to ``center__o-pl…`` names
nothing, a number cut to ``1800 / …`` is not a number, and a path loses its end, which is the
part that says which run it is. The commands build their tables here: numbers and labels stay
whole, headers and descriptions give up the room, and a path in a title is shortened in its
middle (:mod:`povagent.run.narrow_console`). Nothing here prints.
"""

from __future__ import annotations

from typing import Any, NamedTuple

from povagent.run.narrow_console import middle_ellipsis

__all__ = ["PathTitle", "console_width", "fitted_table", "middle_ellipsis", "path_in_line"]


class PathTitle(NamedTuple):
    """A table title naming a folder or file: ``before``, the path, ``after``; the path is the
    part shortened (in its middle) when the title's first line is wider than its table.
    ``after`` may go on with more lines (a line break in it), each short enough to fit."""

    path: object
    after: str = ""
    before: str = ""


def console_width() -> int:
    """The width rich prints to: ``COLUMNS``, else the terminal's, else 80."""
    from rich.console import Console

    return Console().width

#: How a column's cells behave when the table is too wide: ``label`` (slice, cell and plugin
#: names: wrap at spaces, fold a long word, never cut), ``number`` (kept whole on one line;
#: its header goes on two lines when that saves room), ``text`` (descriptions: wrap at spaces).
COLUMN_KINDS = ("label", "number", "text")


def fitted_table(
    columns: list[tuple[str, str]],
    rows: list[list[str]],
    *,
    title: str | PathTitle | None = None,
    caption: str | None = None,
    width: int | None = None,
) -> Any:
    """A rich table of ``rows`` under ``columns`` (``(header, kind)``, kind from :data:`COLUMN_KINDS`)
    for a console ``width`` wide (default: the terminal's).

    Rich narrows a table by shrinking its widest columns, numbers included, and then cuts
    words; here only labels and text give up room: when the natural table is too wide, number
    headers go on two lines, and labels and text wrap. A :class:`PathTitle` is fitted to the
    table's width by shortening its path in the middle.
    """
    from rich.table import Table

    width = console_width() if width is None else width
    for header, kind in columns:
        if kind not in COLUMN_KINDS:
            raise ValueError(f"column {header!r}: kind {kind!r} is not one of {COLUMN_KINDS}")
    plain_rows = [[_plain(c) for c in row] for row in rows]

    def table_width(headers: list[str]) -> int:
        # each column: its widest line, one space of padding either side, one border
        cells = [max([len(x) for x in h.split("\n")] + [len(r[i]) for r in plain_rows if i < len(r)]) for i, h in enumerate(headers)]
        return sum(cells) + 3 * len(headers) + 1

    headers = [h for h, _ in columns]
    if table_width(headers) > width:
        headers = [_two_lines(h) if kind == "number" else h for h, kind in columns]
    if isinstance(title, PathTitle):
        room = min(width, table_width(headers)) - len(title.before)
        first, sep, more = title.after.partition("\n")
        title = title.before + path_in_line(title.path, first, width=room) + sep + more
    table = Table(title=title, caption=caption)
    for header, (_, kind) in zip(headers, columns):
        if kind == "number":
            table.add_column(header, justify="right", no_wrap=True)
        elif kind == "label":
            table.add_column(header, overflow="fold")
        else:
            table.add_column(header)
    for row in rows:
        table.add_row(*row)
    return table


def _two_lines(header: str) -> str:
    """``header`` broken at the space nearest its middle (unchanged without a space)."""
    spaces = [i for i, ch in enumerate(header) if ch == " "]
    if not spaces:
        return header
    cut = min(spaces, key=lambda i: abs(len(header) - 2 * i))
    return header[:cut] + "\n" + header[cut + 1 :]


def _plain(cell: str) -> str:
    """A cell's visible text (rich markup such as ``[bold]`` takes no room)."""
    from rich.text import Text

    return Text.from_markup(cell).plain


def path_in_line(path: object, rest: str = "", width: int | None = None) -> str:
    """``path`` followed by ``rest`` (`` (center / basic / json)``), the path shortened in its
    middle so that the line fits ``width`` (default: the terminal's); never below 24 characters."""
    width = console_width() if width is None else width
    return middle_ellipsis(str(path), max(24, width - len(rest))) + rest
