"""One field of many rows, held without an object a row: what a run summary keeps per key.

A :class:`Column` stores each value in a byte: ``None``, ``True``, ``False``, a small whole
number or a repeated text (a label: a condition, a status, a parser's name) is the byte; a
float or a larger whole number adds a double (8 bytes more), and a column holding none has no
doubles at all. Any other value (a rare third-party field) is kept aside as the object it is.
Reading a position gives back an equal value of the same type (the same object for texts), so
numbers summed from a column are the numbers summed from the rows.

Pure storage: it knows no row and no summary (:mod:`povagent.run.summary_table` fills it).
"""

from __future__ import annotations

import sys
from array import array
from collections.abc import Iterable
from typing import Any

import numpy as np

_NONE, _FLOAT, _TRUE, _FALSE, _INT, _TEXT, _ASIDE = range(7)
#: Kinds from here on are a small whole number (kind - _SMALL) held in the kind byte alone ...
_SMALL = 8
#: ... and from here on a text's code (kind - _CODE), for a column's first 128 texts.
_CODE = 128
#: Texts whose code the kind byte holds (a column's first ones).
_NEAR_TEXTS = 256 - _CODE
#: Whole numbers a double holds exactly.
_EXACT = 2**53
#: What :meth:`Column.values` marks a value read on its own with (no value equals it).
_SPECIAL = object()


class Column:
    """The values of one field, a row each, appended in order (see the module's docstring)."""

    __slots__ = ("_numbers", "_kinds", "_texts", "_text_code", "_aside")

    def __init__(self) -> None:
        # made at the first value a byte cannot hold: a column of flags or labels has none
        self._numbers: array | None = None
        self._kinds = bytearray()
        self._texts: list[str] = []
        self._text_code: dict[str, int] = {}
        self._aside: dict[int, Any] = {}

    def __len__(self) -> int:
        return len(self._kinds)

    def append(self, value: Any) -> None:
        """Add ``value`` as the next row's."""
        self.extend((value,))

    def extend(self, values: Iterable[Any]) -> None:
        """Add each of ``values`` as the next rows' (a summary adds a batch of rows a column at a time)."""
        if type(values) is list and len(values) > 1 and values.count(values[0]) == len(values) and len(set(map(id, values))) == 1:
            # one object in every row of the batch (most of a run's columns: its condition, its
            # status, its unset fields): placed once, its byte (and number) repeated
            self._repeat(values[0], len(values))
            return
        kinds, text_code = self._kinds, self._text_code
        for value in values:
            # the common values first (a flag, None, a label already met, a small count): the
            # byte alone, no branch more
            if value is None:
                kind = _NONE
            elif value is True:
                kind = _TRUE
            elif value is False:
                kind = _FALSE
            elif type(value) is str and (code := text_code.get(value, _NEAR_TEXTS)) < _NEAR_TEXTS:
                kind = _CODE + code
            elif type(value) is int and 0 <= value < _CODE - _SMALL:
                kind = _SMALL + value
            elif type(value) is float and self._numbers is not None:  # a cost, a latency: its double
                self._numbers.append(value)
                kinds.append(_FLOAT)
                continue
            else:
                self._append_other(value)
                continue
            if self._numbers is not None:
                self._numbers.append(0.0)
            kinds.append(kind)

    def _repeat(self, value: Any, times: int) -> None:
        """Add ``value`` as the next ``times`` rows' (what :meth:`extend` of it ``times`` times adds)."""
        self.extend((value,))
        kind = self._kinds[-1]
        if kind == _ASIDE:  # kept aside by position: each row its own entry
            self.extend((value,) * (times - 1))
            return
        self._kinds += bytes((kind,)) * (times - 1)
        if self._numbers is not None:
            self._numbers.extend(array("d", (self._numbers[-1],)) * (times - 1))

    def _append_other(self, value: Any) -> None:
        """Add a value :meth:`extend` did not place by its byte alone (never None, a flag or a
        small count): a float before the first number, an int, a text not met yet or coded
        past the near ones, anything else (kept aside)."""
        kind, number = _ASIDE, None
        t = type(value)
        if t is float:
            kind, number = _FLOAT, value
        elif t is int and -_EXACT <= value <= _EXACT:
            kind, number = _INT, float(value)
        elif t is str:
            code = self._text_code.get(value)
            if code is None:
                code = self._text_code[value] = len(self._texts)
                self._texts.append(sys.intern(value))
            kind, number = (_CODE + code, None) if code < 256 - _CODE else (_TEXT, float(code))
        if kind == _ASIDE:
            self._aside[len(self._kinds)] = value
        if number is not None and self._numbers is None:
            self._numbers = array("d", bytes(8 * len(self._kinds)))
        if self._numbers is not None:
            self._numbers.append(0.0 if number is None else number)
        self._kinds.append(kind)

    def __getitem__(self, i: int) -> Any:
        kind = self._kinds[i]
        if kind >= _CODE:
            return self._texts[kind - _CODE]
        if kind >= _SMALL:
            return kind - _SMALL
        if kind == _FLOAT:
            return self._numbers[i]  # type: ignore[index]  # a float's column has its numbers
        if kind == _NONE:
            return None
        if kind == _TRUE:
            return True
        if kind == _FALSE:
            return False
        if kind == _INT:
            return int(self._numbers[i])  # type: ignore[index]
        if kind == _TEXT:
            return self._texts[int(self._numbers[i])]  # type: ignore[index]
        return self._aside[i]

    def values(self) -> list[Any]:
        """Every row's value, in order: ``[column[i] for i in range(len(column))]``, read in one
        pass (a summary reads every row of a dozen columns)."""
        by_kind: list[Any] = [_SPECIAL] * 256
        by_kind[_NONE], by_kind[_TRUE], by_kind[_FALSE] = None, True, False
        for kind in range(_SMALL, _CODE):
            by_kind[kind] = kind - _SMALL
        for code, text in enumerate(self._texts[: 256 - _CODE]):
            by_kind[_CODE + code] = text
        out = [by_kind[kind] for kind in self._kinds]
        if _SPECIAL in out:  # numbers, far texts and values kept aside: one at a time
            out = [self[i] if value is _SPECIAL else value for i, value in enumerate(out)]
        return out

    def taken(self, positions: np.ndarray, new_position: np.ndarray) -> Column:
        """The rows at ``positions`` (in that order) as a column of their own; ``new_position``
        maps each old position to its new one (-1: not taken)."""
        out = Column.__new__(Column)
        out._numbers = None if self._numbers is None else array("d", np.frombuffer(self._numbers, dtype=np.float64)[positions].tobytes())
        out._kinds = bytearray(np.frombuffer(bytes(self._kinds), dtype=np.uint8)[positions].tobytes())
        out._texts, out._text_code = self._texts, self._text_code
        out._aside = {int(new_position[old]): v for old, v in self._aside.items() if new_position[old] >= 0}
        return out

    def nbytes(self) -> int:
        """Bytes the column holds (its arrays; texts and kept-aside values not counted)."""
        return len(self._kinds) + (0 if self._numbers is None else 8 * len(self._numbers))
