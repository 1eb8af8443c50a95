"""The report's "Why it fails" section and the gallery's diagnostics, on planted runs, in Chromium.

Three runs over the session's generated set, scored with ``official``, ``diagnose`` and
``relation``: a planted simulation that always answers the egocentric target, one that answers
the ground truth, and the random baseline. What the page shows is checked against the rows the
runs wrote (the report never rescores).
"""

from __future__ import annotations

import asyncio
import html
import re
from collections import Counter

import pytest
from session_browser import KEPT_IN_STORAGE, kept_page
from test_report_html import SCRIPT_RAN, body_attr, cards, dump  # the Chromium helpers

from povagent.config.pipeline import ConfigSource, pipeline_from_source
from povagent.report.build import write_report
from povagent.results.rows import iter_rows
from povagent.run.runner import PipelineRun

SYSTEMS = {
    "ego": {"name": "planted", "options": {"egocentric": 1.0, "pixel_sigma": 2, "seed": 0}},
    "truth": {"name": "planted", "options": {"pixel_sigma": 2, "seed": 0}},
    "random": {"name": "random", "options": {"seed": 0}},
}


@pytest.fixture(scope="module")
def diagnosed(generated_release, tmp_path_factory):
    """(sweep folder, {run name: rows}) of the three runs, over the set's first house (its 57
    instances hold every condition and direction; the gallery draws a card per row)."""
    folder = tmp_path_factory.mktemp("why") / "sweep"
    rows = {}
    for name, backend in SYSTEMS.items():
        config = pipeline_from_source(ConfigSource("<test>", {
            "dataset": {"path": str(generated_release)}, "instances": {"houses": ["train_house_00000"]},
            "backend": backend, "strategy": "basic", "parser": "official",
            "scorers": ["official", "diagnose", "relation"], "cache": False, "output": str(folder / name),
        }, {}))  # fmt: skip
        asyncio.run(PipelineRun(config).run())
        rows[name] = list(iter_rows(folder / name / "results.jsonl"))
    return folder, rows


@pytest.fixture(scope="module")
def report(diagnosed, tmp_path_factory):
    return write_report(diagnosed[0], tmp_path_factory.mktemp("why-report") / "out", n_boot=200)


@pytest.fixture(scope="module")
def page(report) -> str:
    return report.page.read_text(encoding="utf-8")


def ego_system(report) -> str:
    return next(s.system for s in report.analysis.systems if "egocentric 1.0" in s.system)


def steps_link(page: str, system: str, step: str) -> str:
    row = re.search(rf'<tr data-system="{re.escape(html.escape(system))}">.*?</tr>', page.split('id="table-failure_steps"')[1], re.S).group(0)
    return html.unescape(re.search(rf'<a href="([^"]+)" data-step="{step}">', row).group(1))


def test_the_section_has_a_bar_per_system_and_condition_and_a_menu_entry(page, report):
    assert '<a href="#why">Why it fails</a>' in page
    section = page.split('<section id="why">')[1].split("</section>")[0]
    figure = section.split('<figure id="fig-failure_steps">')[1].split("</figure>")[0]
    assert figure.count('<text x="292"') == 3 * 3  # a condition label per bar: 3 systems x A, B, C
    assert (report.out / "plots" / "failure_steps.svg").stat().st_size > 0
    # every part is a link to those answers in the gallery
    assert re.search(r'<a href="#system=[^"]+&amp;cond=a&amp;step=viewpoint"><rect [^>]*data-part="viewpoint"', figure)


def test_the_step_shares_are_those_of_the_rows(page, report, diagnosed):
    _, rows = diagnosed
    steps = Counter(r.scores["diagnose"]["step"] for r in rows["ego"] if r.scores.get("diagnose", {}).get("answered"))
    ego = ego_system(report)
    row = re.search(rf'<tr data-system="{re.escape(html.escape(ego))}">.*?</tr>', page.split('id="table-failure_steps"')[1], re.S).group(0)
    shown = re.findall(r'data-step="(\w+)">([\d.]+)%</a>', row)
    total = sum(steps.values())
    assert {k: float(v) for k, v in shown} == pytest.approx({k: round(100 * steps[k] / total, 1) for k, _ in shown}, abs=0.051)
    assert steps["viewpoint"] > 0


def test_a_link_shows_every_viewpoint_failure_of_a_model(page, report, diagnosed, browser):
    _, rows = diagnosed
    ego = ego_system(report)
    link = steps_link(page, ego, "viewpoint")
    dom = dump(browser, report.page, state=link.lstrip("#"))
    expected = sum(1 for r in rows["ego"] if r.scores.get("diagnose", {}).get("step") == "viewpoint")
    assert expected > 0 and body_attr(dom, "data-gallery-shown") == expected
    shown = cards(dom)
    assert shown and all(c["step"] == "viewpoint" and html.unescape(c["system"]) == ego for c in shown)


def test_cards_draw_the_egocentric_and_mirrored_targets_only_when_asked(report, diagnosed, browser):
    _, rows = diagnosed
    ego = ego_system(report)
    stored = {(r.instance_id, r.scores["diagnose"]["step"]): r.scores["diagnose"] for r in rows["ego"] if r.scores.get("diagnose", {}).get("answered")}
    system = ego.replace(" · ", "/")
    plain = dump(browser, report.page, state=f"system={system}&step=viewpoint")
    plain_grid = plain.split('<div id="gallery">')[1].split("<script")[0]
    assert cards(plain) and 'class="cf-ego"' not in plain_grid and 'class="cf-mir"' not in plain_grid
    drawn = dump(browser, report.page, state=f"system={system}&step=viewpoint&cf=1")
    grid = drawn.split('<div id="gallery">')[1].split("<script")[0]
    marks = re.findall(r'<div class="card" data-i="\d+"[^>]*>.*?<div class="id">([^<]+) · run', grid, re.S)
    ego_marks = re.findall(r'<g class="cf-ego" data-u="([^"]+)" data-v="([^"]+)">', grid)
    mirror_marks = re.findall(r'<g class="cf-mir" data-u="([^"]+)" data-v="([^"]+)">', grid)
    assert marks and len(ego_marks) == len(mirror_marks) == len(marks)
    for iid, (u, v), (mu, mv) in zip(marks, ego_marks, mirror_marks):
        d = stored[(html.unescape(iid), "viewpoint")]
        assert (float(u), float(v)) == pytest.approx(tuple(d["egocentric"]), abs=1e-4)
        assert (float(mu), float(mv)) == pytest.approx(tuple(d["mirrored"]), abs=1e-4)


def test_the_bias_index_is_shown_with_its_interval(page, report):
    ego = next(s for s in report.analysis.systems if "egocentric 1.0" in s.system)
    cell = ego.diagnostics["per_condition"]["a"]
    row = re.search(rf'<tr data-system="{re.escape(html.escape(ego.system))}">.*?</tr>', page.split('id="table-egocentric_bias"')[1], re.S).group(0)
    text = re.search(r'<td data-cond="a">(.*?)</td>', row).group(1)
    lo, hi = cell["egocentric_bias_ci"]
    assert f"{cell['egocentric_bias']:.2f}" in text and f"[{lo:.2f}, {hi:.2f}]" in text and f"n {cell['bias_n']}" in text
    assert cell["egocentric_bias"] == 1.0  # every vote of an always-egocentric model


def test_relation_success_sits_beside_the_official_l2_per_direction(page, report):
    truth = next(s for s in report.analysis.systems if "planted" in s.system and "egocentric" not in s.system)
    table = page.split('id="table-relation"')[1].split("</table>")[0]
    row = re.search(rf'<tr data-system="{re.escape(html.escape(truth.system))}" data-cond="b">.*?</tr>', table, re.S).group(0)
    per = truth.diagnostics["per_condition"]["b"]["per_direction"]
    for direction, cell in per.items():
        text = re.search(rf'<td data-dir="{direction}">(.*?)</td>', row).group(1)
        assert f"{100 * cell['relation_success']:.1f}%" in text and f"L2 {cell['official_mean_l2']:.3f}" in text


def test_a_link_inside_the_page_filters_the_gallery(report, browser):
    """The section's links change the address's fragment in the page itself: the gallery follows."""
    ego = ego_system(report).replace(" · ", "/")
    page = kept_page(browser, (1200, 900))  # a new document in the module's page (tests/session_browser.py)
    page.goto(report.page.as_uri(), wait_until="load", timeout=90_000)
    page.wait_for_function(SCRIPT_RAN, timeout=90_000)
    # the gallery's next render sets data-gallery-page again: cleared first, it says the page followed
    page.evaluate("state => { document.body.removeAttribute('data-gallery-page'); location.hash = state; }", f"system={ego}&step=correct")
    page.wait_for_function("() => document.body.hasAttribute('data-gallery-page')", timeout=90_000)
    shown = int(page.evaluate("() => document.body.getAttribute('data-gallery-shown')"))
    steps = page.evaluate("() => Array.from(document.querySelectorAll('#gallery .card'), c => c.getAttribute('data-step'))")
    assert page.evaluate(KEPT_IN_STORAGE) == 0, "the page wrote to the browser's storage: the next load would see it"
    expected = sum(1 for o in report.analysis.observations if o.system == ego_system(report) and o.fail_step == "correct" and o.run == 0)
    assert expected > 0 and shown == expected and set(steps) == {"correct"}


def test_a_report_without_diagnose_scores_has_no_section_and_no_step_filter(sweep_dir, tmp_path, browser):
    plain = write_report(sweep_dir, tmp_path / "out", n_boot=0, gallery_limit=5)
    text = plain.page.read_text(encoding="utf-8")
    assert '<section id="why">' not in text and 'href="#why"' not in text
    dom = dump(browser, plain.page)
    assert re.search(r'<label id="f-step-wrap" style="display: none;">', dom)
    assert re.search(r'<label id="f-cf-wrap" style="display: none;">', dom)
