"""Fitting one piece of console text into a narrow terminal (80 columns and less).

Rich shortens text by cutting its end off, which is the part of a path that says which run or
file it is. The rule here, used by the run's progress bar and by the CLI's tables and titles:
a path too long for its place keeps its beginning and, with the larger share, its end, around
an ellipsis. Pure text functions: nothing here prints.
"""

from __future__ import annotations

#: What stands for the cut-out middle of a shortened path.
ELLIPSIS = "…"


def middle_ellipsis(text: str, width: int) -> str:
    """``text`` if it fits in ``width`` characters, else its start and end around ``…``.

    The end gets two thirds of the room: of a path, the last folders name the run or the file.
    """
    if len(text) <= width:
        return text
    if width <= len(ELLIPSIS):
        return ELLIPSIS[:max(width, 0)]
    keep = width - len(ELLIPSIS)
    head = keep // 3
    return text[:head] + ELLIPSIS + text[len(text) - (keep - head):]

