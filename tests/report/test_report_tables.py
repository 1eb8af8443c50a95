"""The paper's tables: numbers equal to the official scorer's, rendered in every format."""

from __future__ import annotations

import csv
import io
from collections import defaultdict

import pytest
from table_rows import system_row

from povagent.report.analysis import analyze
from povagent.report.baseline import CENTER_SYSTEM, center_score
from povagent.report.collect import collect
from povagent.report.paper_tables import main_table, paper_tables, response_table
from povagent.report.run_sets import load_collection_dataset
from povagent.report.tables import Cell, Column, Row, Table, to_csv, to_html, to_latex, to_markdown
from povagent.results.rows import read_rows
from povagent.scoring.breakdown import ScoredRow, breakdown


def analysis_of(path, n_boot=200):
    c = collect(path)
    ds, note = load_collection_dataset(c)
    return analyze(c, ds, note, n_boot=n_boot)


def scorer_per_run(run_dir):
    """The official summary (povagent.scoring.breakdown) of each run index of a run folder."""
    by_run = defaultdict(list)
    for r in read_rows(run_dir / "results.jsonl"):
        off = r.scores["official"]
        by_run[r.run].append(ScoredRow(r.condition, r.direction, bool(off["answered"]), off["l2"], off["gt_in_frame"], off["l2_strict"]))
    return [breakdown(rows) for _, rows in sorted(by_run.items())]


def test_main_table_numbers_equal_the_scorers_mean_over_runs(run_dir):
    a = analysis_of(run_dir)
    row = system_row(main_table(a), "mock-a · basic")
    runs = scorer_per_run(run_dir)
    assert len(runs) == 2
    for j, c in enumerate(a.conditions):
        expected = sum(b["per_condition"][c]["mean_l2"] for b in runs) / len(runs)
        assert row.cells[j].value == pytest.approx(expected, abs=1e-12)


def test_response_rate_table_equals_the_scorers(run_dir):
    a = analysis_of(run_dir)
    row = system_row(response_table(a), "mock-a · basic")
    runs = scorer_per_run(run_dir)
    for j, c in enumerate(a.conditions):
        assert row.cells[j].value == pytest.approx(sum(b["per_condition"][c]["response_rate"] for b in runs) / 2, abs=1e-12)
    assert row.cells[-1].value == pytest.approx(sum(b["overall"]["response_rate"] for b in runs) / 2, abs=1e-12)


def test_strict_mean_and_frame_accuracy_equal_the_scorers(run_dir):
    a = analysis_of(run_dir)
    s = a.system("mock-a · basic").overall
    runs = scorer_per_run(run_dir)
    assert s.strict.value == pytest.approx(sum(b["overall"]["mean_l2_strict"] for b in runs) / 2, abs=1e-12)
    assert 100 * s.in_frame.value == pytest.approx(sum(b["overall"]["pct_in_frame"] for b in runs) / 2, abs=1e-9)


def test_every_mean_has_a_ci_around_it(run_dir):
    for cell in system_row(main_table(analysis_of(run_dir)), "mock-a · basic").cells:
        assert cell.lo <= cell.value <= cell.hi


def test_center_baseline_is_computed_and_shown_beside_the_models(run_dir, mini_dataset):
    a = analysis_of(run_dir)
    row = system_row(main_table(a), CENTER_SYSTEM)
    assert row.reference
    given = [i for i in mini_dataset.instances(conditions=["c"])]
    expected = sum(center_score(i).l2 for i in given) / len(given)
    assert row.cells[a.conditions.index("c")].value == pytest.approx(expected)


def test_ablation_table_appears_only_when_strategies_vary(run_dir, sweep_dir):
    assert "ablation" not in [t.key for t in paper_tables(analysis_of(run_dir))]
    tables = {t.key: t for t in paper_tables(analysis_of(sweep_dir))}
    assert [r.label for r in tables["ablation"].rows if not r.reference] == ["mock-a · basic", "mock-a · cot", "mock-b · basic", "mock-b · cot"]
    assert tables["ablation"].columns[-1].name == "Resp."


def small_table():
    t = Table("t", "T", "caption 50% & more", "Model", [Column("Inferred"), Column("Resp.", "rate", "higher")])
    t.rows = [
        Row("m_1", [Cell(0.30, 0.25, 0.35), Cell(0.9)]),
        Row("m_2", [Cell(0.20, 0.15, 0.25), Cell(0.8)]),
        Row("center", [Cell(0.10), Cell(1.0)], reference=True),
    ]
    return t


def test_best_value_per_column_is_bold_in_markdown():
    md = to_markdown(small_table())
    assert "| m_2 | **0.200** [0.150, 0.250] | 80.0% |" in md
    assert "| m_1 | 0.300 [0.250, 0.350] | **90.0%** |" in md


def test_reference_row_is_never_bold_even_when_it_is_best():
    t = small_table()
    for text in (to_markdown(t), to_latex(t), to_html(t)):
        assert "**0.100**" not in text and "\\textbf{0.100}" not in text and '<span class="best">0.100' not in text


def test_latex_is_booktabs_with_escaped_text_and_bold_best():
    tex = to_latex(small_table())
    assert "\\toprule" in tex and "\\midrule" in tex and "\\bottomrule" in tex
    assert "m\\_2 & \\textbf{0.200}" in tex
    assert "50\\% \\& more" in tex


def test_csv_keeps_full_precision_and_flags_the_best():
    rows = list(csv.DictReader(io.StringIO(to_csv(small_table()))))
    assert rows[1]["Model"] == "m_2" and rows[1]["Inferred best"] == "1" and float(rows[1]["Inferred ci_lo"]) == 0.15
    assert rows[2]["reference"] == "1"


def test_ties_at_the_displayed_precision_are_all_bold():
    t = Table("t", "T", "", "Model", [Column("x")], [Row("a", [Cell(0.2001)]), Row("b", [Cell(0.1998)]), Row("c", [Cell(0.5)])])
    md = to_markdown(t)
    assert md.count("**0.200**") == 2


def test_a_sweep_with_its_own_center_cell_gets_no_computed_baseline(sweep_with_center):
    a = analysis_of(sweep_with_center)
    labels = [(s.system, s.reference) for s in a.systems]
    assert (CENTER_SYSTEM, True) not in labels
    assert ("center", True) in labels and ("mock-a · basic", False) in labels


def test_a_baseline_crossed_with_strategies_it_ignores_is_shown_once(make_sweep):
    cells = [
        {"model": "mock-a", "strategy": "basic", "seed": 1},
        {"model": "mock-a", "strategy": "cot", "seed": 1},  # same answers, but a model: kept apart
        {"model": "center", "strategy": "basic", "seed": 2, "noise": 0.0},
        {"model": "center", "strategy": "cot", "seed": 2, "noise": 0.0},
    ]
    a = analysis_of(make_sweep(cells), n_boot=0)
    assert [(s.system, s.reference) for s in a.systems] == [("mock-a · basic", False), ("mock-a · cot", False), ("center", True)]
    assert any("shown once as 'center'" in n for n in a.notes)
    assert {o.system for o in a.observations} == {"mock-a · basic", "mock-a · cot", "center"}
    # the merged baseline is the center the models are compared with
    assert {c.a for c in a.comparisons if c.b == "mock-a · cot"} >= {"center"}


def test_main_table_equals_the_mean_of_povagent_score_over_each_runs_official_export(run_dir, mini_dataset, tmp_path):
    from povagent.report.export import export_run
    from povagent.results.prediction_files import score_predictions

    a = analysis_of(run_dir, n_boot=0)
    files = export_run(run_dir, tmp_path / "p.json")
    scored = [score_predictions(f, mini_dataset)[0] for f in files]
    assert len(scored) == 2
    main = system_row(main_table(a), "mock-a · basic")
    for j, c in enumerate(a.conditions):
        assert main.cells[j].value == pytest.approx(sum(s["per_condition"][c]["mean_l2"] for s in scored) / 2, abs=1e-12)
    resp = system_row(response_table(a), "mock-a · basic")
    assert resp.cells[-1].value == pytest.approx(sum(s["overall"]["response_rate"] for s in scored) / 2, abs=1e-12)


def test_bold_marks_the_best_model_per_column_of_a_real_sweep_never_a_baseline(sweep_dir):
    from povagent.report.tables import best_rows, format_value

    t = main_table(analysis_of(sweep_dir, n_boot=0))
    best = best_rows(t)
    for j, col in enumerate(t.columns):
        shown = {i: float(format_value(r.cells[j].value, col.kind)) for i, r in enumerate(t.rows) if not r.reference and r.cells[j].value is not None}
        assert best[j] == {i for i, v in shown.items() if v == min(shown.values())}
        assert not any(t.rows[i].reference for i in best[j])
