"""The report's Active section: active beside passive on the same instances (paired), the
actions used, L2 against the budget, trajectories with the views each rendered."""

from __future__ import annotations

import html
import json
import re
import shutil

import pytest
import yaml
from test_report_html import VIEWER_SETTLED, dump  # the Chromium helpers

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.report.floor_plan import WALL_COLOUR
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(scope="module")
def report(generated_release, tmp_path_factory):
    root = tmp_path_factory.mktemp("active-report")
    for name, backend, strategy, parser in (("center", "center", "basic", "json"),
                                            ("oracle", "explorer-oracle", "active", "active")):  # fmt: skip
        (root / f"{name}.yaml").write_text(yaml.safe_dump({
            "dataset": {"path": str(generated_release)}, "instances": {"houses": ["train_house_00000"], "sample": 3, "seed": 2},
            "backend": backend, "strategy": strategy, "parser": parser, "scorers": ["official"],
            "output": str(root / "runs" / name)}))  # fmt: skip
        run_pipeline(load_pipeline(root / f"{name}.yaml"))
    return write_report(root / "runs", root / "report", n_boot=200)


def test_each_active_system_is_compared_with_the_passive_run_on_the_same_instances(report):
    overall = [c for c in _active(report)["comparisons"] if c["condition"] == "all"]
    assert len(overall) == 1 and overall[0]["n_pairs"] == 3
    assert overall[0]["mean_b"] < 0.01 and overall[0]["passive"].startswith("center")


def test_the_actions_used_and_the_budget_are_tabled(report):
    numbers = _active(report)
    assert numbers["actions"][0]["episodes"] == 3 and sum(numbers["actions"][0]["actions"].values()) == 3
    assert [b["budget"] for b in numbers["budgets"]] == [8]


def test_trajectories_are_drawn_with_the_views_they_rendered(report):
    page = report.page.read_text()
    assert 'id="active"' in page and page.count('class="active-episode"') == 3
    thumbs = list((report.out / "images" / "active").glob("*.jpg"))
    assert thumbs and all(f"images/active/{t.name}" in page for t in thumbs)


def test_the_gallery_card_shows_the_rendered_view_answered_in_and_the_trajectory_from_above(report):
    svgs = [p.read_text() for p in (report.out / "images").glob("*.svg")]
    assert sum('id="trajectory"' in s for s in svgs) == 3  # one bird's-eye card per active row
    assert report.gallery.without_image == 0  # every active row answered in a view has its drawing


def test_the_caption_says_that_ask_tells_inferred_the_stated_sentence_unless_kept_to_the_condition(report):
    section = report.page.read_text().split('id="active"', 1)[1].split("</p>", 1)[0]
    assert "In Inferred (A), <code>ask</code> answers with the Stated sentence" in section
    assert "<code>speaker: condition</code>" in section and "A and B nearly meet" in section


def test_the_explorer_oracle_is_a_baseline_styled_and_sorted_as_the_passive_oracle_would_be(report):
    reference = {s["system"]: s["reference"] for s in json.loads((report.out / "summary.json").read_text())["systems"]}
    oracle = next(name for name in reference if "explorer-oracle" in name)
    assert reference[oracle] and all(reference.values())  # the centre guess too: two baselines
    tables = (report.out / "tables.md").read_text()
    assert f"| *{oracle}* |" in tables and "**0.000" not in tables


def oracle_records(report) -> list:
    from povagent.results.episode import read_record
    from povagent.results.rows import read_rows

    return [read_record(r.exchanges[-1].raw) for r in read_rows(report.out.parent / "runs" / "oracle" / "results.jsonl")]


def test_each_trajectory_caption_rounds_every_argument_and_cuts_nothing_without_an_ellipsis(report):
    from povagent.report.step_caption import step_caption

    page = report.page.read_text()
    captions = re.findall(r'<div class="active-episode">.*?<p class="muted">(.*?)</p>', page, re.S)
    expected = [", ".join(step_caption(s.action, s.arguments) for s in r.steps) for r in oracle_records(report)]
    assert sorted(captions) == sorted(html.escape(c) for c in expected)
    assert all(re.search(r"\d\.\d{3}", c) is None for c in captions)  # no number shown beyond two decimals


def test_the_maps_from_above_draw_the_house_floor_plan_under_the_path(report, generated_release):
    from povagent.active.house import house_for

    plan = house_for(generated_release, "train_house_00000").built.house.plan
    walls = sum(1 for s in plan.slabs if s.y0 == 0.0)
    page = report.page.read_text()
    cards = re.findall(r'<div class="active-episode">(.*?)</svg>', page, re.S)
    assert len(cards) == 3
    for card in cards:
        drawn = card.split('<g id="floor-plan">', 1)[1].split("</g>", 1)[0]
        assert drawn.count(f'fill="{WALL_COLOUR}"') == walls and drawn.count("<text") == len(plan.rooms)
        assert card.index('id="floor-plan"') < card.index("<polyline")  # under the path
    trajectories = [p.read_text() for p in (report.out / "images").glob("*.svg") if 'id="trajectory"' in p.read_text()]
    assert len(trajectories) == 3 and all(s.index('id="floor-plan"') < s.index('id="trajectory"') for s in trajectories)


def _active(report) -> dict:
    import json

    return json.loads((report.out / "summary.json").read_text())["active"]


def test_the_gallery_card_carries_every_view_the_episode_rendered_as_a_strip(report):
    data = gallery_data(report)
    active = [e for e in data["entries"] if e.get("vs") is not None]
    assert len(active) == 3  # the oracle's rows; the centre baseline's have none
    for e in active:
        strip = data["strips"][e["vs"]]
        assert strip["n"] >= 1 and (report.out / "images" / f"{strip['k']}.s.jpg").is_file()
        assert e["va"] is None or 1 <= e["va"] <= strip["n"]


def test_the_opened_card_shows_the_rendered_views_numbered_with_the_answered_one_outlined(report, browser):
    data = gallery_data(report)
    entries = data["entries"]
    first = next(e for e in entries if e.get("vs") is not None and e.get("va"))
    system = data["systems"][first["s"]]
    dom = dump(browser, report.page, state=f"system={system}&open=0", until=VIEWER_SETTLED)
    tiles = re.findall(r'<div class="tile( sel)?" data-view="(\d+)"', dom)
    assert [int(n) for _, n in tiles] == list(range(1, data["strips"][first["vs"]]["n"] + 1))
    assert [int(n) for sel, n in tiles if sel] == [first["va"]]
    assert "The views it rendered" in dom


def gallery_data(report) -> dict:
    html = report.page.read_text(encoding="utf-8")
    return json.loads(re.search(r'<script type="application/json" id="gallery-data">(.*?)</script>', html, re.S).group(1))


@pytest.mark.timeout(90)
def test_views_planted_in_a_run_folder_are_not_read_and_the_report_is_written(report, tmp_path):
    import os

    runs = tmp_path / "runs"
    shutil.copytree(report.out.parent / "runs", runs)
    views = sorted((runs / "oracle" / "views").glob("*.png"))
    fifo, linked = views[0], views[1]
    outside = tmp_path / "outside.png"
    outside.write_bytes(linked.read_bytes())
    fifo.unlink()
    os.mkfifo(fifo)  # opened by path, it would wait for a writer forever
    linked.unlink()
    linked.symlink_to(outside)
    again = write_report(runs, tmp_path / "report", n_boot=0)
    thumbs = {p.stem for p in (again.out / "images" / "active").glob("*.jpg")}
    assert thumbs and fifo.stem not in thumbs and linked.stem not in thumbs
