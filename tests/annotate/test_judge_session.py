"""Judge mode in a real browser: a real-world run's predictions judged blind, a judge session
killed midway resumed, two judges' overlap, and the report's manual tables."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from served_page import Served

from povagent.results.judgements import read_judgements

pytestmark = pytest.mark.slow

REALWORLD_DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"


@pytest.fixture(scope="module")
def realworld_run(tmp_path_factory):
    """A run of the centre baseline on the demo real-world set: six predictions to judge."""
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    base = tmp_path_factory.mktemp("judge")
    (base / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(REALWORLD_DEMO)},
        "backend": "center",
        "strategy": "basic", "parser": "json", "scorers": ["success"],
        "output": str(base / "runs" / "model-a"),
    }))  # fmt: skip
    run_pipeline(load_pipeline(base / "pipeline.yaml"))
    return base


def judge_yaml(base: Path, judge: str) -> Path:
    path = base / f"{judge}.yaml"
    path.write_text(yaml.safe_dump({"judge": judge, "runs": ["runs/model-a"]}))
    return path


def judge_on_page(page, key: str) -> None:
    page.wait_for_selector("#view[src]")
    page.wait_for_function("() => !document.getElementById('marker').hidden")
    before = page.locator("#progress").text_content()
    page.keyboard.press(key)
    page.keyboard.press("Enter")
    page.wait_for_function("(before) => document.getElementById('progress').textContent !== before", arg=before)


@pytest.fixture(scope="module")
def judged(realworld_run, browser):
    """carol judges two predictions, her server is killed, she judges the rest; dave judges all,
    disagreeing with her on the second one he sees."""
    base = realworld_run
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.set_default_timeout(120_000)  # a loaded machine: the first question may take a while
    served = Served(judge_yaml(base, "carol"))
    try:
        page.goto(served.url)
        page_text = page.locator("body").text_content()
        judge_on_page(page, "s")
        judge_on_page(page, "f")
    finally:
        served.kill()
    after_kill = read_judgements(base / "runs" / "judgements" / "carol.jsonl")
    served = Served(judge_yaml(base, "carol"))
    try:
        page.goto(served.url)
        page.wait_for_selector("#view[src]")
        while not page.locator("#status").text_content().startswith("All done"):
            judge_on_page(page, "s")
        served.wait()
    finally:
        served.kill()
    served = Served(judge_yaml(base, "dave"))
    try:
        page.goto(served.url)
        page.wait_for_selector("#view[src]")
        keys = iter(["s", "c"])
        while not page.locator("#status").text_content().startswith("All done"):
            judge_on_page(page, next(keys, "s"))
        served.wait()
    finally:
        served.kill()
        page.close()
    return base, page_text, after_kill


def test_a_judge_sees_no_system_name(judged):
    _, page_text, _ = judged
    assert "model-a" not in page_text and "center" not in page_text and "house_1" not in page_text


def test_a_killed_judge_session_keeps_what_it_saved_and_resumes_with_nothing_twice(judged):
    base, _, after_kill = judged
    assert [j.verdict for j in after_kill] == ["success", "failure"]
    carol = read_judgements(base / "runs" / "judgements" / "carol.jsonl")
    assert carol[:2] == after_kill
    assert len({j.item for j in carol}) == len(carol) == 6  # every answered prediction once


def test_the_report_shows_the_manual_table_and_the_judges_kappa(judged, tmp_path):
    from povagent.report.build import write_report

    base, _, _ = judged
    result = write_report(base / "runs" / "model-a", tmp_path / "report", gallery=False, n_boot=50)
    keys = [t.key for t in result.tables]
    assert "manual_success" in keys and "manual_agreement" in keys
    html = result.page.read_text(encoding="utf-8")
    assert "Manual assessment" in html and "carol / dave" in html
