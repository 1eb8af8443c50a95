"""Comparing two runs instance by instance (povagent/report/compare.py)."""

from __future__ import annotations

import re

import pytest

from povagent.report.collect import collect
from povagent.report.compare import compare_runs, write_comparison_html


def per_instance(path):
    acc = {}
    for o in collect(path).observations:
        if o.answered:
            acc.setdefault(o.instance_id, []).append(o.l2)
    return {k: sum(v) / len(v) for k, v in acc.items()}


def test_a_run_compared_with_itself_changes_nothing(run_dir):
    cmp = compare_runs(run_dir, run_dir, n_boot=100)
    assert all(d.delta in (None, 0.0) for d in cmp.deltas)
    assert cmp.overall.ties == cmp.overall.n_pairs and cmp.overall.sign_p is None


def test_per_instance_delta_is_b_minus_a_of_run_averaged_errors(sweep_dir):
    a, b = sweep_dir / "cell_00", sweep_dir / "cell_02"
    cmp = compare_runs(a, b, n_boot=100)
    ea, eb = per_instance(a), per_instance(b)
    both = [d for d in cmp.deltas if d.change == "both"]
    assert both
    for d in both:
        assert d.delta == pytest.approx(eb[d.instance_id] - ea[d.instance_id])
    assert {d.instance_id for d in cmp.deltas if d.change == "only_a"} == set(ea) - set(eb)


def test_most_changed_lists_the_largest_absolute_differences_first(sweep_dir):
    cmp = compare_runs(sweep_dir / "cell_00", sweep_dir / "cell_02", n_boot=100)
    top = [abs(d.delta) for d in cmp.most_changed(5) if d.delta is not None]
    assert top == sorted(top, reverse=True)
    assert top[0] == max(abs(d.delta) for d in cmp.deltas if d.delta is not None)


def test_compare_html_shows_both_runs_drawings_side_by_side(sweep_dir, tmp_path, mini_dataset):
    cmp = compare_runs(sweep_dir / "cell_00", sweep_dir / "cell_02", n_boot=100)
    page = write_comparison_html(cmp, tmp_path, mini_dataset).read_text()
    assert '"img_b":"' in page and '"dl":' in page
    for key in set(re.findall(r'"img(?:_b)?":"([0-9a-f]{64})"', page)):
        assert (tmp_path / "images" / f"{key}.t.jpg").exists()


def test_compare_cards_show_the_run_averaged_errors_the_delta_is_made_of(run_dir, sweep_dir, tmp_path, mini_dataset):
    import json

    cmp = compare_runs(run_dir, sweep_dir / "cell_02", n_boot=0)  # A has two runs, B one
    page = write_comparison_html(cmp, tmp_path, mini_dataset).read_text()
    data = json.loads(re.search(r'<script type="application/json" id="gallery-data">(.*?)</script>', page, re.S).group(1))
    deltas = {d.instance_id: d for d in cmp.deltas}
    assert data["entries"]
    for e in data["entries"]:
        d = deltas[e["id"]]
        assert e["nr"] == 2
        assert e["ma"] == (None if d.a is None else round(d.a, 4)) and e["mb"] == (None if d.b is None else round(d.b, 4))
        assert "a" not in e and "a_b" not in e  # raw answers are in answers/*.js


def test_comparing_a_sweep_of_several_systems_asks_for_run_folders(sweep_dir, run_dir):
    from povagent.errors import PredictionsError

    with pytest.raises(PredictionsError, match="holds 4 systems"):
        compare_runs(sweep_dir, run_dir, n_boot=0)
