"""The report puts the official parse beside the numbers of a system parsed leniently."""

from __future__ import annotations

import re

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.report.build import write_report
from povagent.report.collect import collect
from povagent.report.official_beside import official_beside_table

runner = CliRunner()

#: Who answered: a model (the answers below are a model's, not a baseline's).
MODEL = {"name": "litellm", "options": {"model": "openai/gpt-4o-mini"}}

#: json answers all three (trailing comma repaired, single quotes read); the official runner one.
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200,}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 100}'),
    ("train_house_00000/0/front/c", "{'x': 200, 'y': 300}"),
]


@pytest.fixture
def run_parsed_with(tmp_path, write_answered_run):
    """``run_parsed_with(parser)``: the answers above, rescored with ``parser``."""

    def rescored(parser: str):
        run = write_answered_run(tmp_path / "raw", ANSWERS, backend=MODEL)
        assert runner.invoke(app, ["rescore", str(run), "--parser", parser, "--json"]).exit_code == 0
        return run / f"rescored-{parser}"

    return rescored


def test_a_lenient_system_gets_its_official_numbers_beside(tmp_path, mini_root, run_parsed_with):
    table = official_beside_table(collect(run_parsed_with("json")))
    assert table is not None
    names = [c.name for c in table.columns]
    assert names == ["Given L2 repaired", "Given resp. repaired", "Given L2 official", "Given resp. official"]
    (row,) = table.rows
    assert "(json)" in row.label
    assert row.cells[1].value == 1.0 and abs(row.cells[3].value - 1 / 3) < 1e-12


def test_an_official_system_is_not_listed(tmp_path, mini_root, run_parsed_with):
    assert official_beside_table(collect(run_parsed_with("official"))) is None


def test_the_report_writes_the_table(tmp_path, mini_root, run_parsed_with):
    folder = run_parsed_with("json")
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=50)
    text = (tmp_path / "report" / "tables" / "official_parse_beside.md").read_text()
    assert "Official parse beside the repaired numbers" in text
    assert any(t.key == "official_parse_beside" for t in result.tables)


def test_a_baseline_is_never_listed(sweep_with_center):
    """A baseline writes its own answers, no repair changes them: only the model has a row,
    and it names its parser."""
    table = official_beside_table(collect(sweep_with_center))
    assert [row.label.split(" ")[0] for row in table.rows] == ["mock-a"]
    assert "(json" in table.rows[0].label


def test_a_repair_that_changed_no_answer_is_not_listed(tmp_path, write_answered_run):
    clean = [(key, '{"x": 100, "y": 100}') for key, _ in ANSWERS]
    run = write_answered_run(tmp_path / "raw", clean, backend=MODEL)
    assert runner.invoke(app, ["rescore", str(run), "--parser", "json", "--json"]).exit_code == 0
    assert official_beside_table(collect(run / "rescored-json")) is None


def page_widths(browser, page, window: tuple[int, int]) -> dict[str, int]:
    """The document's scroll width, the viewport's width and the official-parse table's width,
    measured in headless Chromium (window ``window``) on a copy of ``page`` with a measuring
    script added."""
    from test_report_html import rendered

    copy = page.with_name("measured.html")
    script = (
        "<script>window.addEventListener('load', function () {"
        "var b = document.body, t = document.getElementById('table-official_parse_beside');"
        "b.setAttribute('data-scroll-width', document.documentElement.scrollWidth);"
        "b.setAttribute('data-viewport-width', document.documentElement.clientWidth);"
        "b.setAttribute('data-table-width', Math.round(t.getBoundingClientRect().width));"
        "});</script>"
    )
    copy.write_text(page.read_text(encoding="utf-8").replace("</body>", script + "</body>"), encoding="utf-8")
    dom = rendered(browser, copy.as_uri(), window=window, until="() => document.body.hasAttribute('data-table-width')")
    return {k: int(v) for k, v in re.findall(r'data-(scroll-width|viewport-width|table-width)="(\d+)"', dom)}


def test_the_table_scrolls_in_its_own_box_and_the_page_does_not(sweep_with_center, tmp_path, browser):
    """Three conditions make twelve number columns: wider than a laptop's window. The page
    itself must not scroll sideways (measured in Chromium at 1024 px); the table does, in its box."""
    result = write_report(sweep_with_center, tmp_path / "report", gallery=False, n_boot=50)
    widths = page_widths(browser, result.page, (1024, 800))
    assert 0 < widths["viewport-width"] <= 1024, widths
    assert widths["table-width"] > widths["viewport-width"], widths  # the table is wider than the window...
    assert widths["scroll-width"] <= widths["viewport-width"], widths  # ...and the page does not scroll sideways
    wide = page_widths(browser, result.page, (1900, 800))
    assert wide["table-width"] <= 1500, wide  # headers and system names wrap: on a wide screen it fits
