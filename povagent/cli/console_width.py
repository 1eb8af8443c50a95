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

import re
from typing import Any, NamedTuple

from povagent.run.narrow_console import middle_ellipsis

__all__ = ["PathTitle", "break_between_words", "console_width", "fitted_table", "fitted_tables", "middle_ellipsis", "path_in_line", "stacked_number"]

#: Where a name or path may go on to the next line, best first: after a space, ``/`` or ``__``
#: (between a sweep cell's parts); then after ``.``, ``_``, ``-``, ``=`` or ``:``. A piece is a
#: word with the separators after it.
_PIECES = (re.compile(r"(?:(?! |/|__).)+(?: |/|__)*|(?: |/|__)+"), re.compile(r"[^ /._\-=:]+[ /._\-=:]*|[ /._\-=:]+"))


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
        cells = [max([len(x) for x in h.split("\n")] + [len(x) for r in plain_rows if i < len(r) for x in r[i].split("\n")]) for i, h in enumerate(headers)]
        return sum(cells) + 3 * len(headers) + 1

    headers = [h for h, _ in columns]
    if table_width(headers) > width:
        headers = [_two_lines(h) if kind == "number" else h for h, kind in columns]
    if table_width(headers) > width:
        # a number with its interval and count goes on lines of its own: each part stays whole
        rows = [
            [stacked_number(c) if kind == "number" and c == p else c for c, p, (_, kind) in zip(row, plain, columns)] for row, plain in zip(rows, plain_rows)
        ]
        plain_rows = [[_plain(c) for c in row] for row in rows]
    label_widths: dict[int, int] = {}
    if table_width(headers) > width:
        # labels that do not fit go on several lines, broken between words (a cell name's
        # parts), never inside one as rich's fold would
        rows = [list(row) for row in rows]
        for i, (_, kind) in enumerate(columns):
            if kind != "label":
                continue
            own = max([len(x) for x in headers[i].split("\n")] + [len(r[i]) for r in plain_rows if i < len(r)])
            room = max(width - (table_width(headers) - own), max(len(x) for x in headers[i].split("\n")), 4)
            for r, plain in zip(rows, plain_rows):
                if i < len(r) and len(plain[i]) > room and r[i] == plain[i]:  # markup-free: broken as it is
                    r[i] = break_between_words(r[i], room)
                    plain[i] = r[i]
            label_widths[i] = max([len(x) for r in rows if i < len(r) for x in _plain(r[i]).split("\n")] + [len(x) for x in headers[i].split("\n")])
    if isinstance(title, PathTitle):
        room = min(width, table_width(headers)) - len(title.before)
        first, sep, more = title.after.partition("\n")
        title = title.before + path_in_line(title.path, first, width=room) + sep + more
    table = Table(title=title, caption=caption)
    for i, (header, (_, kind)) in enumerate(zip(headers, columns)):
        if kind == "number":
            table.add_column(header, justify="right", no_wrap=True)
        elif kind == "label":
            table.add_column(header, overflow="fold", min_width=label_widths.get(i))
        else:
            table.add_column(header)
    for row in rows:
        table.add_row(*row)
    return table


def stacked_number(cell: str) -> str:
    """``66.7% [33.3%, 100.0%] n=6`` as three lines: the value, its interval, its count."""
    return re.sub(r" (?=\[)|(?<=\]) ", "\n", cell)


def fitted_tables(
    columns: list[tuple[str, str]],
    rows: list[list[str]],
    *,
    title: str | PathTitle | None = None,
    caption: str | None = None,
    width: int | None = None,
) -> list[Any]:
    """:func:`fitted_table`, as several tables when its number columns cannot stand side by
    side in ``width`` even stacked: each table repeats the label columns (so every row keeps
    its name) with as many number columns as fit; the title goes on the first, the caption on
    the last."""
    width = console_width() if width is None else width
    numbers = [i for i, (_, kind) in enumerate(columns) if kind == "number"]
    labels = [i for i, (_, kind) in enumerate(columns) if kind != "number"]

    def narrowest(i: int) -> int:  # a column's width with its header on two lines and its numbers stacked
        lines = _two_lines(columns[i][0]).split("\n") + [x for r in rows if i < len(r) for x in stacked_number(_plain(r[i])).split("\n")]
        return max(len(x) for x in lines) + 3

    # a label column may wrap, but not below its longest word (a slice's name stays readable)
    label_room = sum(min(24, max([len(w) for r in rows if i < len(r) for w in _plain(r[i]).split()] + [len(columns[i][0])])) + 3 for i in labels)
    groups: list[list[int]] = [[]]
    used = label_room + 1
    for i in numbers:
        if groups[-1] and used + narrowest(i) > width:
            groups.append([])
            used = label_room + 1
        groups[-1].append(i)
        used += narrowest(i)
    if len(groups) == 1:
        return [fitted_table(columns, rows, title=title, caption=caption, width=width)]
    tables = []
    for k, group in enumerate(groups):
        keep = sorted(labels + group)
        tables.append(
            fitted_table(
                [columns[i] for i in keep],
                [[r[i] for i in keep if i < len(r)] for r in rows],
                title=title if k == 0 else None,
                caption=caption if k == len(groups) - 1 else None,
                width=width,
            )
        )
    return tables


def break_between_words(text: str, room: int) -> str:
    """``text`` on lines of at most ``room`` characters, broken only after a separator, never
    inside a word: after a space, ``/`` or ``__`` where that is enough, else also after ``.``,
    ``_``, ``-``, ``=`` or ``:``; a word longer than ``room`` keeps a line to itself, whole.
    A space where a line breaks is dropped; any other separator stays at the end of its line,
    so the lines joined give the text back."""
    return "\n".join(_pack(text, room, 0))


def _pack(text: str, room: int, level: int) -> list[str]:
    lines: list[str] = []
    line = ""
    for piece in _PIECES[level].findall(text):
        if len(piece.rstrip(" ")) > room and level + 1 < len(_PIECES):
            if line:
                lines.append(line.rstrip(" ") or line)
            *whole, line = _pack(piece, room, level + 1)
            lines += whole
        elif line and len(line) + len(piece.rstrip(" ")) > room:
            lines.append(line.rstrip(" ") or line)
            line = piece
        else:
            line += piece
    lines.append(line)
    return lines


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
