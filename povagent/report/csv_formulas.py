"""Spreadsheet formulas in CSV cells: text that a spreadsheet would run is written inert.

What it is for: povagent's CSV files (the long CSV of ``povagent export --format long-csv``,
the report's table CSVs) hold text a model or a run folder chose: a model's raw answer, a
sentence, a model label. Opened in Excel, LibreOffice or Google Sheets, a cell starting with
``=``, ``+``, ``-`` or ``@`` (or a tab or a carriage return before one) is read as a formula,
and a formula can fetch URLs or, through DDE, start programs (OWASP, "CSV Injection"). As OWASP
advises, such a text cell is written with a single quote before it (``'=HYPERLINK(...)``):
spreadsheets show it as text, and the quote is the one change. The rule, exactly:

* only text cells are guarded; a number povagent writes as a number (an ``int`` or a
  ``float``, such as ``-0.5`` or ``-3``) is written as it is, and so is a text cell that is a
  plain decimal number in ASCII digits (``-0.5``, ``+3``, ``-1e-05``: a spreadsheet reads it
  as that number);
* a text cell whose first character is ``=``, ``+``, ``-``, ``@``, a tab or a carriage return
  gets a ``'`` before it; every other cell is written unchanged.

A reader that wants the model's exact answer back removes one leading ``'`` from a cell that
starts with ``'`` followed by one of those characters. What it must not do: change a number,
or any cell that no spreadsheet reads as a formula.
"""

from __future__ import annotations

import re

#: The first characters that make a spreadsheet read a cell as a formula (OWASP's list).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
#: Text a spreadsheet reads as a plain number, never a formula (ASCII digits only).
_PLAIN_NUMBER = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?")


def inert(cell: object) -> object:
    """``cell`` as a CSV file may hold it: a text cell a spreadsheet would read as a formula gets
    a single quote before it; anything else is returned unchanged."""
    if isinstance(cell, str) and cell.startswith(FORMULA_STARTS) and not _PLAIN_NUMBER.fullmatch(cell):
        return "'" + cell
    return cell
