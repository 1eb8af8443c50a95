"""One object for each distinct value a report's rows repeat: labels, texts and numbers.

A collection holds one observation a row; the strings and floats in them repeat across rows
(a run's labels, an instance's sentence and ground truth in every run, a baseline's answer
given again). Each table here makes equal values one object while a collection is read, and
is dropped with it: unlike :func:`sys.intern`, whose table never shrinks.

Pure: nothing here reads or writes files.
"""

from __future__ import annotations

from typing import Any, Callable


def label_table() -> Callable[[str], str]:
    """What makes equal strings one object, from a table of its own."""
    labels: dict[str, str] = {}

    def share(text: str) -> str:
        return labels.setdefault(text, text)

    return share


def number_table() -> Callable[[Any], Any]:
    """What makes equal floats one object, from a table of its own; any other value is
    returned as it is.

    Only floats that no other value equals yet prints otherwise: never an int (``1 == 1.0``),
    a zero (``-0.0 == 0.0``) or a NaN (equal to nothing, so never found again)."""
    table: dict[float, float] = {}

    def same(value: Any) -> Any:
        if type(value) is float and value and value == value:
            return table.setdefault(value, value)
        return value

    return same
