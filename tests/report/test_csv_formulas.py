"""A CSV cell a spreadsheet would run as a formula is written after a single quote (OWASP's
advice); numbers, plain-number text and every other cell are written as they are."""

from __future__ import annotations

import csv
import io

import pytest

from povagent.report.csv_formulas import inert
from povagent.report.tables import Cell, Column, Row, Table, to_csv


@pytest.mark.parametrize("cell", ["=1+1", "+cmd|' /C calc'!A0", "-", "-1+1", "-inf", "-\u0663", "@SUM(A1)", "\t=1", "\r=1"])
def test_text_starting_a_formula_gets_a_single_quote(cell):
    assert inert(cell) == "'" + cell


@pytest.mark.parametrize("cell", [-0.5, -3, "-0.5", "+3", "-1e-05", ".5", "hello", "a=b", " =1", "", None, True])
def test_numbers_plain_number_text_and_other_cells_are_unchanged(cell):
    assert inert(cell) is cell


def test_a_report_table_writes_a_label_inert_and_its_numbers_as_numbers():
    table = Table("t", "title", "", "system", [Column("mean L2")], [Row('=HYPERLINK("http://x")', [Cell(-0.25)])])
    header, line = csv.reader(io.StringIO(to_csv(table)))
    assert line[0] == "'=HYPERLINK(\"http://x\")" and line[header.index("mean L2")] == "-0.25"
