"""A choice run's console tables in an 80-column terminal: every row keeps its name and every
number, interval and count stays whole, however many metrics its scorer declares (3DSRBench's
five); a relation run lists each direction once."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def _rows(text: str) -> list[str]:
    """The first cell of every table line (a row's name, or a continued line's blank)."""
    return [line.split("│")[1].strip() for line in text.splitlines() if line.startswith("│")]


def test_3dsrbench_console_tables_keep_every_row_name_and_number_in_80_columns(choice_pipeline):
    config = choice_pipeline("3dsrbench", backend="test-center", reply="A", scorers=("choice-3dsrbench",))
    result = runner.invoke(app, ["run", str(config), "--quiet"], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    shown = result.stdout
    assert max(len(line) for line in shown.splitlines()) <= 80, shown
    names = [n for n in _rows(shown) if n]
    # every table repeats the slices: each row is named in each, none cut
    assert {"overall", "category 'height_higher'", "category 'orientation_on_the_left'"} <= set(names), shown
    assert [line for line in shown.splitlines() if line.startswith(("│", "┃")) and "…" in line] == [], shown
    for label in ("Vanilla", "Flip", "Circular", "Flip+Circular", "Response rate"):
        assert label in shown
    # always "A": vanilla 4 of 6, its interval and count whole
    assert "66.7%" in shown and "n=6" in shown


def test_a_category_equal_to_a_direction_is_listed_once():
    from povagent.cli.slice_rows import breakdown_slices
    from povagent.run.summary_model import MetricEstimate, ScorerMetrics

    cell = {"accuracy": MetricEstimate(value=0.5, ci_lo=0.0, ci_hi=1.0, n=2)}
    other = {"accuracy": MetricEstimate(value=1.0, ci_lo=1.0, ci_hi=1.0, n=1)}
    metrics = ScorerMetrics.model_construct(overall=cell, per_condition={}, per_direction={"right": cell}, per_category={"right": cell, "kitchen": other})
    assert [label for label, _ in breakdown_slices(metrics)] == ["overall", "right", "category 'kitchen'"]


def test_a_relation_run_lists_each_direction_once(tmp_path, generated_release, offline_plugin_file):
    config = tmp_path / "relation.yaml"
    config.write_text(yaml.safe_dump({
        "plugins": [str(offline_plugin_file)], "dataset": {"path": str(generated_release)}, "task": "relation",
        "backend": {"name": "test-center", "options": {"reply": "A"}}, "strategy": "choice", "scorers": ["choice"],
        "instances": {"sample": 6, "seed": 1}, "runs": 1, "concurrency": 2, "timeout": 5, "output": str(tmp_path / "run"),
    }))  # fmt: skip
    result = runner.invoke(app, ["run", str(config), "--quiet"], env={"COLUMNS": "100"})
    assert result.exit_code == 0, result.output
    names = [n for n in _rows(result.stdout) if n]
    assert not any(n.startswith("category ") for n in names), result.stdout
    directions = [n for n in names if n in ("right", "left", "front", "behind", "up", "down", "on", "under")]
    assert directions and len(directions) == len(set(directions)), result.stdout
