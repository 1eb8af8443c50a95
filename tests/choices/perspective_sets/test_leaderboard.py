"""The leaderboard over choice runs: systems x sets, each cell the set's own number with its CI,
the harness readings folded under it; runs of different sets never pooled into one row.

Real runs on two sets in their published formats (the ViewSpatial-Bench fixture: gold A, B, A,
C; the MindCube fixture: gold A, C, B), each answered by three systems labelled alike on both
sets: the ``oracle``, always "A", and a reply reading "(b)" (a lower-case letter some rules read
and others do not).
"""

from __future__ import annotations

import csv
import io
import json

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.report.leaderboard import LEADERBOARD, READINGS, choice_readers
from povagent.run.runner import run_pipeline

SYSTEMS = (("oracle", "oracle", None), ("always-a", "test-center", "A"), ("lower-b", "test-center", "(b)"))
SETS = ("viewspatial", "mindcube")


@pytest.fixture(scope="module")
def two_sets_three_systems(tmp_path_factory, module_choice_pipeline):
    """A folder of six runs: each of :data:`SYSTEMS` on each of :data:`SETS`, labelled by system
    (made once for the module: its tests only read them)."""
    folder = tmp_path_factory.mktemp("leaderboard") / "runs"
    results = {}
    for format in SETS:
        for label, backend, reply in SYSTEMS:
            path = module_choice_pipeline(format, backend=backend, reply=reply)
            data = yaml.safe_load(path.read_text()) | {"label": label, "output": str(folder / f"{format}-{label}")}
            path.write_text(yaml.safe_dump(data, sort_keys=False))
            results[(label, format)] = run_pipeline(load_pipeline(path))
    return folder, results


def _table(result, key):
    return next(t for t in result.tables if t.key == key)


def _grid(table):
    return {r.label: {c.name: cell.value for c, cell in zip(table.columns, r.cells)} for r in table.rows}


@pytest.fixture(scope="module")
def report(two_sets_three_systems, tmp_path_factory):
    folder, results = two_sets_three_systems
    return write_report(folder, tmp_path_factory.mktemp("leaderboard-report") / "report", gallery=False, n_boot=200), results


def test_the_leaderboard_has_a_row_per_system_and_a_column_per_set(report):
    result, _ = report
    table = _table(result, LEADERBOARD)
    assert [c.name for c in table.columns] == ["mindcube", "viewspatial"]
    assert sorted(r.label for r in table.rows) == ["always-a", "lower-b", "oracle"]


def test_each_leaderboard_cell_is_the_sets_own_number_of_that_run(report):
    result, results = report
    grid = _grid(_table(result, LEADERBOARD))
    for (label, format), run in results.items():
        assert grid[label][format] == pytest.approx(run.summary.metrics["choice"].overall["accuracy"].value), (label, format)
    # always "A": 2 of 4 ViewSpatial questions (gold A twice), 1 of 3 MindCube ones
    assert grid["always-a"] == {"viewspatial": pytest.approx(0.5), "mindcube": pytest.approx(1 / 3)}


def test_the_leaderboard_names_each_sets_number_and_the_rule_that_read_it(report):
    result, results = report
    caption = _table(result, LEADERBOARD).caption
    for format in SETS:
        parser = results[("oracle", format)].summary.pipeline.parser
        assert f"{format}: Accuracy (choice), read by `{parser}`" in caption


def test_a_leaderboard_cell_carries_its_confidence_interval(report):
    result, _ = report
    row = next(r for r in _table(result, LEADERBOARD).rows if r.label == "always-a")
    assert all(c.lo is not None and c.hi is not None and c.lo <= c.value <= c.hi for c in row.cells)


def test_runs_of_two_sets_under_one_label_are_never_one_system(report):
    result, _ = report
    systems = [s.system for s in result.analysis.systems]
    assert sorted(systems) == sorted(f"{label} · {format}" for label, _, _ in SYSTEMS for format in SETS)
    assert not result.poolings or all(len({p.split("-")[0] for p in pooling.runs}) == 1 for pooling in result.poolings)


def test_each_set_has_its_own_accuracy_table(report):
    result, _ = report
    viewspatial = _grid(_table(result, "choice_accuracy_choice_viewspatial"))
    mindcube = _grid(_table(result, "choice_accuracy_choice_mindcube"))
    assert viewspatial["always-a · viewspatial"]["All"] == pytest.approx(0.5)
    assert mindcube["always-a · mindcube"]["All"] == pytest.approx(1 / 3)
    assert set(viewspatial) == {f"{label} · viewspatial" for label, _, _ in SYSTEMS}


def test_the_harness_readings_read_each_reply_by_every_choice_rule(report):
    from povagent.answers.spec import AnswerSpec, choice_answer_schema
    from povagent.plugins import get_plugin_host

    result, _ = report
    readings = _table(result, READINGS)
    rules = choice_readers()
    assert [c.name for c in readings.columns] == ["Questions"] + rules and readings.folded_under == LEADERBOARD
    # "(b)" on ViewSpatial: right only where gold is B (question 2 of 4) for a rule reading B, else never
    options = (("A", "front"), ("B", "back"), ("C", "left"), ("D", "right"))
    spec = AnswerSpec(schema=choice_answer_schema(("A", "B", "C", "D")), width=512, height=512, asks_frame=False, choices=options)
    host = get_plugin_host()
    row = _grid(readings)["lower-b · viewspatial"]
    assert row["Questions"] == 4
    golds = "ABAC"  # the ViewSpatial-Bench fixture's, in file order
    for rule in rules:
        # a rule with a fallback label (OmniSpatial's re and json read A) scores where the gold is it
        label = host.parser(rule, {}).parse("(b)", spec).choice
        assert row[rule] == pytest.approx(golds.count(label) / 4 if label else 0.0), rule
    assert len({row[rule] for rule in rules}) >= 2  # the rules disagree on it: that is why the readings are shown


def test_the_leaderboard_is_exported_as_csv_and_latex(report):
    result, _ = report
    text = (result.out / "tables" / f"{LEADERBOARD}.csv").read_text(encoding="utf-8")
    rows = {r["System"]: r for r in csv.DictReader(io.StringIO(text))}
    assert set(rows) == {"oracle", "always-a", "lower-b"}
    assert float(rows["always-a"]["viewspatial"]) == pytest.approx(0.5) and rows["always-a"]["viewspatial ci_lo"] != ""
    latex = (result.out / "tables" / f"{LEADERBOARD}.tex").read_text(encoding="utf-8")
    assert "mindcube" in latex and "viewspatial" in latex and "always-a" in latex
    assert (result.out / "tables" / f"{READINGS}.csv").is_file()
    summary = json.loads((result.out / "summary.json").read_text(encoding="utf-8"))
    assert summary["tables"][LEADERBOARD]["columns"] == ["mindcube", "viewspatial"]


def test_the_harness_readings_open_with_one_click_under_the_leaderboard(report):
    result, _ = report
    page = result.page.read_text(encoding="utf-8")
    board = page.index(f'id="table-{LEADERBOARD}"')
    folded = page.index(f'<details class="folded" id="folded-{READINGS}">')
    assert board < folded < page.index(f'id="table-{READINGS}"')


def test_a_baseline_is_never_bolded_in_the_per_category_table(report):
    result, _ = report
    table = _table(result, "choice_accuracy_choice_viewspatial")
    from povagent.report.tables import best_rows

    assert all(r.reference for r in table.rows)  # oracle and test-center: offline baselines
    assert best_rows(table) == [set() for _ in table.columns]
    body = (result.out / "tables" / "choice_accuracy_choice_viewspatial.md").read_text(encoding="utf-8").split("\n", 1)[1]
    assert "**" not in body


def test_the_report_command_prints_the_leaderboard(two_sets_three_systems, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    folder, _ = two_sets_three_systems
    outcome = CliRunner().invoke(app, ["report", str(folder), "--out", str(tmp_path / "printed"), "--no-gallery", "--bootstrap", "50"])
    assert outcome.exit_code == 0, outcome.output
    assert "**Leaderboard: systems x sets**" in outcome.stdout
    assert "| System | mindcube | viewspatial |" in outcome.stdout
