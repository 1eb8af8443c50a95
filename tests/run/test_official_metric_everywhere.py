"""A metric added to the official scorer reaches every command that shows the official score.

The official scorer declares its metrics once (``OfficialScorer.metrics``) and lists its row
fields once (``OfficialScorer.point_fields``); ``povagent run``'s summary and console,
``povagent rescore``, ``povagent score`` and ``povagent report`` read both from the scorer. A
maintainer's change is simulated by an official scorer with one metric more (the mean squared
error, over a field of its own), registered in place of the built-in one: no other file knows
of it, and each command shows its value (never ``-``, never skipped).
"""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from povagent import hookimpl
from povagent.cli import app
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.scoring.metrics import Metric
from povagent_plugins.scorers.official_scorer import OFFICIAL_METRICS, OfficialScorer

BUILT_IN = "povagent_plugins.scorers.official_scorer"
SQUARED = Metric("mean_squared_l2", "lower", "mean", "l2_squared", "Squared L2", "Mean squared official L2 over answered instances.")


class SquaredOfficialScorer(OfficialScorer):
    """The official scorer with one metric more, as a maintainer would add it."""

    metrics = (*OFFICIAL_METRICS, SQUARED)

    def point_fields(self, point, l2_closest=None):
        fields = super().point_fields(point, l2_closest)
        if point.l2 is not None:
            fields["l2_squared"] = point.l2**2
        return fields


class _Plugin:
    @hookimpl
    def register_scorers(self, register):
        register("official", SquaredOfficialScorer, description="official, with the squared error")


@pytest.fixture
def squared_official(povagent_host):
    """The built-in official scorer replaced by :class:`SquaredOfficialScorer` for the test."""
    builtin = povagent_host.pm.get_plugin(BUILT_IN)
    povagent_host.remove_plugin(BUILT_IN)
    name = povagent_host.add_plugin(_Plugin(), name="test-squared-official")
    try:
        yield
    finally:
        povagent_host.remove_plugin(name)
        povagent_host.add_plugin(builtin, name=BUILT_IN, source=f"built-in {BUILT_IN}")


@pytest.fixture
def squared_run(tmp_path, write_pipeline, squared_official):
    """A run scored by the extended official scorer: its folder, console output and the mean
    squared error of its rows (computed here from each row's official ``l2``)."""
    result = CliRunner().invoke(app, ["run", str(write_pipeline())], env={"COLUMNS": "250"})
    assert result.exit_code == 0, result.output
    folder = tmp_path / "run"
    errors = [r.scores["official"]["l2"] for r in read_rows(folder / "results.jsonl") if r.scores["official"].get("l2") is not None]
    assert errors and len({round(e, 6) for e in errors}) > 1  # a mean of distinct numbers, not one repeated
    return folder, result.stdout, sum(e * e for e in errors) / len(errors)


def test_the_runs_summary_holds_the_new_metric(squared_run):
    folder, _, expected = squared_run
    official = json.loads((folder / "summary.json").read_text(encoding="utf-8"))["metrics"]["official"]
    assert "mean_squared_l2" in official["declared"]
    assert official["overall"]["mean_squared_l2"]["value"] == pytest.approx(expected)


def test_the_runs_console_shows_the_new_metric(squared_run):
    _, printed, expected = squared_run
    assert "Squared L2 ↓" in printed and f"{expected:.3f}" in printed


def test_rescore_writes_and_prints_the_new_metric(squared_run, offline_plugin):
    folder, _, expected = squared_run
    rescored = rescore_run(folder, "test-json", plugins=[offline_plugin.__file__])
    assert rescored.summary.metrics["official"].overall["mean_squared_l2"].value == pytest.approx(expected)
    result = CliRunner().invoke(app, ["rescore", str(folder), "--parser", "test-json", "--plugin", offline_plugin.__file__],
                                env={"COLUMNS": "250"})  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "Squared L2 ↓" in result.stdout and f"{expected:.3f}" in result.stdout


def test_score_reports_the_new_metric(squared_run, small_release):
    folder, _, expected = squared_run
    args = ["score", "--predictions", str(folder), "--dataset", str(small_release)]
    result = CliRunner().invoke(app, [*args, "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["metrics"]["official"]["overall"]["mean_squared_l2"]["value"] == pytest.approx(expected)
    printed = CliRunner().invoke(app, args, env={"COLUMNS": "250"}).stdout
    assert "Squared L2 ↓" in printed and f"{expected:.3f}" in printed


def test_the_report_has_a_table_of_the_new_metric(squared_run, tmp_path):
    folder, _, expected = squared_run
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(folder), "--out", str(out), "--bootstrap", "20", "--no-gallery"])
    assert result.exit_code == 0, result.output
    table = (out / "tables" / "metric_official_mean_squared_l2.md").read_text(encoding="utf-8")
    assert "Squared L2 (official)" in table and f"{expected:.3f}" in table
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    (by_system,) = summary["metrics"]["official"].values()
    assert by_system["overall"]["mean_squared_l2"]["value"] == pytest.approx(expected)
