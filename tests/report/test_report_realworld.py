"""Reports of real-world sets (hand-marked GT, scored by ``success``): success tables equal to the
scorer's rows, no official tables, gallery drawings of the marks, the page in headless Chromium.

The sweep fixture (``realworld_sweep`` in conftest.py) is a real sweep on the demo set: the
center baseline and a replayed "model" acting out ``REALWORLD_PLAN``, rows written and scored
by the real runner and the real success scorer.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from table_rows import system_row
from test_report_html import body_attr, cards, dump, gallery_data  # the Chromium helpers

from povagent.dataset.realworld_set import load_realworld
from povagent.report.baseline import CENTER_SYSTEM
from povagent.report.build import write_report
from povagent.report.collect import Observation
from povagent.report.gallery import drawing_for
from povagent.report.gallery_drawing import GT_COLOUR, PRED_COLOUR, render
from povagent.report.paper_tables import success_table
from povagent.results.rows import iter_rows

REALWORLD_DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


@pytest.fixture(scope="module")
def report(realworld_sweep, tmp_path_factory):
    return write_report(realworld_sweep, tmp_path_factory.mktemp("rw_report") / "out", n_boot=200)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return load_realworld(REALWORLD_DEMO, cache_dir=tmp_path_factory.mktemp("rw_letterboxed"))


def scorer_rates(run_dir: Path, condition: str | None = None) -> tuple[float, float]:
    """(success rate, response rate) straight from the rows the runner wrote: per run, hits
    (answered) / rows, a row the scorer did not score counting as an unanswered miss; then the
    mean over runs."""
    per_run: dict[int, list[tuple[bool, bool]]] = defaultdict(list)
    for row in iter_rows(run_dir / "results.jsonl"):
        if condition is None or row.condition == condition:
            s = row.scores.get("success") or {}
            per_run[row.run].append((s.get("success") is True, row.status == "answered" and s.get("answered") is True))
    hits = [sum(h for h, _ in rows) / len(rows) for rows in per_run.values()]
    answered = [sum(a for _, a in rows) / len(rows) for rows in per_run.values()]
    return float(np.mean(hits)), float(np.mean(answered))


def test_success_table_equals_the_success_scorers_rows_per_system_and_condition(report, realworld_sweep):
    table = success_table(report.analysis)
    assert [c.name for c in table.columns] == ["Inferred", "Stated", "Given", "Overall", "Resp."]
    for system, folder in (("replay · basic", "replay"), ("center", "center")):
        row = system_row(table, system)
        for j, condition in enumerate(["a", "b", "c"]):
            assert row.cells[j].value == pytest.approx(scorer_rates(realworld_sweep / folder, condition)[0])
        success, response = scorer_rates(realworld_sweep / folder)
        assert row.cells[3].value == pytest.approx(success) and row.cells[4].value == pytest.approx(response)
    # the plan: run 0 hits 3 of 6 and answers 5, run 1 hits 4 and answers 5
    replay = system_row(table, "replay · basic")
    assert replay.cells[3].value == pytest.approx(7 / 12) and replay.cells[4].value == pytest.approx(10 / 12)
    assert replay.cells[3].lo <= 7 / 12 <= replay.cells[3].hi
    assert system_row(table, "center").reference


def test_official_tables_and_plots_are_left_out_for_a_set_without_official_ground_truth(report):
    assert [t.key for t in report.tables] == ["success", "success_by_direction", "response_rates", "paired"]
    assert not (report.out / "tables" / "main.md").exists()
    assert "Main results" not in (report.out / "tables.md").read_text()
    plots = {p.stem for p in (report.out / "plots").iterdir()}
    assert plots == {"success_by_condition", "success_by_direction"}
    assert report.dataset_note is None  # the real-world set loaded: no "dataset not loadable"


def test_success_tables_are_written_in_markdown_csv_and_latex(report):
    md = (report.out / "tables" / "success.md").read_text()
    assert re.search(r"\| replay · basic \| .* \| 58\.3% \[[\d.]+, [\d.]+\] \| 83\.3% \[[\d.]+, [\d.]+\] \|", md)
    csv = (report.out / "tables" / "success.csv").read_text()
    assert re.search(r"^replay · basic,0,.*,0\.58333333333333\d*,", csv, re.M)  # full precision
    tex = (report.out / "tables" / "success.tex").read_text()
    assert "\\toprule" in tex and "58.3\\%" in tex


def test_summary_json_carries_success_rates_with_cis(report):
    summary = json.loads((report.out / "summary.json").read_text())
    assert summary["scorers"] == ["success"]
    replay = next(s for s in summary["systems"] if s["system"] == "replay · basic")
    assert replay["overall"]["success_rate"]["value"] == pytest.approx(7 / 12)
    assert replay["overall"]["official_mean_l2"]["value"] is None


def test_paired_comparison_on_hit_rates_counts_the_better_system_by_higher_success(report):
    [cmp] = report.analysis.comparisons
    assert (cmp.a, cmp.b, cmp.metric) == ("center", "replay · basic", "success")
    assert cmp.diff.value == pytest.approx(7 / 12) and cmp.b_better > 0 and cmp.a_better == 0


def test_the_center_baseline_is_judged_by_the_success_scorer_when_the_sweep_has_none(realworld_sweep, tmp_path):
    result = write_report(realworld_sweep / "replay", tmp_path / "r", n_boot=0, gallery=False)
    computed = system_row(success_table(result.analysis), CENTER_SYSTEM)
    # the same guess as the sweep's own center cell, scored the same way
    assert computed.cells[3].value == pytest.approx(scorer_rates(realworld_sweep / "center")[0])
    assert computed.cells[4].value == 1.0
    assert any("judged by the runs' success scorer" in n for n in result.analysis.notes)


def observation(instance, x: float, y: float, frame: int | None, radius: float | None) -> Observation:
    return Observation(
        system="m", run_name="r", run=0, instance_id=instance.id, house_id=instance.house_id, pair_id=instance.pair_id,
        direction=str(instance.direction), condition=str(instance.condition), status="answered", parse_status="ok",
        answered=True, l2=None, l2_strict=None, gt_in_frame=None, gt_behind=None, gt_u=None, gt_v=None,
        selected_image=frame, image_path=None, x=x, y=y, sentence=instance.sentence, raw="{}",
        scorer="success", success=False, hit_radius_px=radius,
    )


def near(pixel, colour, tol: int = 60) -> bool:
    return all(abs(int(a) - int(b)) <= tol for a, b in zip(pixel, colour))


def test_gallery_draws_the_marked_point_with_its_hit_radius_in_the_letterboxed_frame(demo):
    inst = demo.instance("house_1/kitchen/right/a")  # a point mark at (540, 310) in frame 1, 1280x720
    radius = 0.1 * math.hypot(1280, 720)
    drawing = drawing_for(observation(inst, 40.0, 150.0, 1, radius), inst)
    [(shape, (mx, my), r)] = drawing.marks
    assert shape == "point" and (mx, my) == pytest.approx((540 * 0.4, 310 * 0.4 + 112)) and r == pytest.approx(radius * 0.4)
    im = np.asarray(render(drawing))
    assert near(im[round(my), round(mx)], GT_COLOUR)  # the mark's centre dot
    assert near(im[150, 40], PRED_COLOUR)  # the predicted point
    with Image.open(drawing.source) as src:
        original = np.asarray(src.convert("RGB")).astype(int)
    inside = (round(my), round(mx + r / 2))  # in the hit zone, off the ring and the dot
    red_drop, green_drop = original[inside][:2] - im[inside][:2].astype(int)
    assert red_drop > green_drop + 20  # tinted green


def test_a_selected_frame_without_a_mark_shows_the_prediction_alone(demo):
    inst = demo.instance("house_1/kitchen/right/a")
    drawing = drawing_for(observation(inst, 100.0, 200.0, 0, None), inst)
    assert drawing.marks == () and drawing.gt_state == "unmarked" and drawing.pred == (100.0, 200.0)


def test_box_and_region_marks_are_mapped_into_the_square(demo):
    box = drawing_for(observation(demo.instance("house_1/kitchen/right/c"), 1, 1, None, None), demo.instance("house_1/kitchen/right/c"))
    assert box.marks == (("box", pytest.approx((196.0, 220.0, 240.0, 248.0))),)
    inst = demo.instance("house_1/bedroom/up/a")
    region = drawing_for(observation(inst, 1, 1, 2, None), inst)
    assert region.marks[0][0] == "region" and region.marks[0][1][0] == pytest.approx((360.0, 276.0))


@pytest.fixture(scope="module")
def dom(report, browser):
    return dump(browser, report.page)


def test_the_page_shows_the_success_table_in_the_browser(dom):
    table = re.search(r'<table class="results" id="table-success".*?</table>', dom, re.S).group(0)
    assert '<th scope="row">replay · basic</th><td>66.7%' in table and '<th scope="row">center</th>' in table
    assert 'id="table-main"' not in dom and 'id="fig-success_by_condition"><svg' in dom


def test_gallery_cards_show_the_frame_and_hit_or_miss_in_the_browser(dom, report):
    assert body_attr(dom, "data-gallery-count") == report.gallery.entries == 12
    assert body_attr(dom, "data-images-loaded") >= 1 and body_attr(dom, "data-images-failed") == 0
    shown = cards(dom)
    assert {c["ok"] for c in shown} == {"0", "1"}
    assert '<span class="badge hit">hit</span>' in dom and '<span class="badge miss">miss</span>' in dom
    assert re.search(r'<div class="card" [^>]*data-ok="1"><div class="imgs"><img alt="[^"]+" src="images/[0-9a-f]{64}\.t\.jpg">', dom)


def test_the_hit_filter_from_the_url_shows_only_hits(report, browser):
    hits = [e for e in gallery_data(report)["entries"] if e["ok"]]
    shown = cards(dump(browser, report.page, "ok=hit"))
    assert len(shown) == len(hits) > 0 and all(c["ok"] == "1" for c in shown)


def test_screenshot_of_the_real_world_report_is_a_rendered_page(report, browser, tmp_path):
    shot = tmp_path / "shot.png"
    dump(browser, report.page, shot=shot, window=(1400, 2600))
    assert shot.exists()
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    assert pixels.std() > 20 and (pixels.mean(axis=2) < 80).mean() > 0.005
    # the gallery's frames are on it: the demo's drawn rooms and the green of the marks
    green = (abs(pixels - np.array(GT_COLOUR)) < 40).all(axis=2)
    assert green.sum() > 50


def test_povagent_report_on_the_demo_run_prints_the_success_table_without_a_warning(tmp_path):
    root = REALWORLD_DEMO.parents[1]
    run = subprocess.run([sys.executable, "-m", "povagent.cli", "run", "examples/realworld_demo/pipeline.yaml", "-o", str(tmp_path / "run"), "-q"],
                         capture_output=True, text=True, cwd=root, timeout=120)
    assert run.returncode == 0, run.stderr
    done = subprocess.run([sys.executable, "-m", "povagent.cli", "report", str(tmp_path / "run"), "--bootstrap", "100"],
                          capture_output=True, text=True, cwd=root, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "warning" not in done.stderr and "not loadable" not in done.stdout + done.stderr
    assert "**Success rate**" in done.stdout and "Main results" not in done.stdout
    success = json.loads((tmp_path / "run" / "summary.json").read_text())["success"]
    expected = f"{100 * success['overall']['success_rate']:.1f}%"
    assert re.search(rf"\| \*center\* \|.*\| {re.escape(expected)} \[[\d.]+, [\d.]+\] \| 100\.0% ", done.stdout)
