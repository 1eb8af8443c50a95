"""A whole answer session in a real browser: a person's clicks become rows of an ordinary run
folder, a killed server resumes at the next instance, and the report shows human:alice."""

from __future__ import annotations

import pytest
from served_page import Served, write_study

from povagent.annotate.order import annotator_order
from povagent.results.rows import iter_rows

pytestmark = pytest.mark.slow


def gt_pixel(instance):
    """(image index in the request, x, y) of the ground truth, in the image's own pixels:
    projected with the instance's cameras (the observer view for Given, else a frame that sees it)."""
    w, h = instance.frame_size
    if not instance.condition.uses_exploration_frames:
        u, v, _ = instance.observer_camera.project_point(instance.target)
        return 0, u * w, v * h
    for k, frame in enumerate(instance.frames):
        u, v, depth = frame.camera.project_point(instance.target)
        if depth > 0 and 0.05 < u < 0.95 and 0.05 < v < 0.95:
            return k, u * w, v * h
    raise AssertionError(f"{instance.id}: no frame sees its ground truth")


def answer_on_page(page, instance):
    """Show the frame that sees the GT, click its pixel (at whatever size the page shows it), submit."""
    k, x, y = gt_pixel(instance)
    page.wait_for_selector("#view[src]")
    if k:
        page.locator("#strip button").nth(k).click()
    view = page.locator("#view")
    page.wait_for_function("() => document.getElementById('view').complete && document.getElementById('view').naturalWidth > 0")
    box = view.bounding_box()
    natural = page.evaluate("() => [document.getElementById('view').naturalWidth, document.getElementById('view').naturalHeight]")
    view.click(position={"x": x * box["width"] / natural[0], "y": y * box["height"] / natural[1]})
    before = page.locator("#progress").text_content()
    page.keyboard.press("Enter")
    page.wait_for_function("(before) => document.getElementById('progress').textContent !== before", arg=before)


@pytest.fixture(scope="module")
def session(browser, tmp_path_factory, mini_root, mini_dataset):
    """Alice answers three instances at 1280x720, clicking each GT pixel; the server is killed
    (SIGKILL) after her second answer and started again with the same command."""
    from povagent.annotate.study_config import load_answer_study
    from povagent.run.pending import select_instances

    folder = tmp_path_factory.mktemp("annotate")
    path = write_study(folder, mini_root, instances={"limit": 3})
    run_dir = folder / "human-alice"
    config = load_answer_study(path).pipeline
    order = [i for i, _ in annotator_order([(i, 0) for i in select_instances(mini_dataset, config)], "alice")]
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.set_default_timeout(120_000)  # a loaded machine: the first question may take a while
    served = Served(path)
    try:
        page.goto(served.url)
        page.wait_for_selector("#view[src]")
        shown = (page.locator("#prompt p").all_text_contents(), page.locator("#strip img").count())
        for instance in order[:2]:
            answer_on_page(page, instance)
    finally:
        served.kill()  # mid-session: the third question is open
    after_kill = list(iter_rows(run_dir / "results.jsonl"))
    served = Served(path)  # the same command, again
    try:
        page.goto(served.url)
        answer_on_page(page, order[2])
        served.wait_all_done(page)
        exit_code = served.wait()
    finally:
        served.kill()
        page.close()
    return order, after_kill, list(iter_rows(run_dir / "results.jsonl")), run_dir, exit_code, shown


def test_the_page_shows_the_strategys_own_request(session):
    from povagent.exchange.images import ImageStore
    from povagent.exchange.messages import TextPart
    from povagent.plugins import get_plugin_host

    order, *_, (texts, n_images) = session
    request = get_plugin_host().strategy("basic", {}).build(order[0], ImageStore())
    assert texts == [p.text for m in request.messages for p in m.parts if isinstance(p, TextPart)]
    assert n_images == len(request.image_hashes())


def test_a_killed_session_keeps_every_answer_it_acknowledged(session):
    order, after_kill, *_ = session
    assert [r.instance_id for r in after_kill] == [i.id for i in order[:2]]


def test_the_session_resumes_at_the_next_instance_with_no_row_doubled(session):
    order, _, rows, _, exit_code, _ = session
    assert [r.instance_id for r in rows] == [i.id for i in order]
    assert exit_code == 0


def test_each_click_on_the_ground_truth_pixel_scores_as_a_hit(session):
    _, _, rows, *_ = session
    for row in rows:
        assert row.scores["official"]["l2"] < 0.01, (row.instance_id, row.exchanges[-1].raw)


def test_each_row_names_the_person_and_how_long_they_looked(session):
    _, _, rows, *_ = session
    for row in rows:
        assert row.model == "human:alice"
        assert row.exchanges[-1].latency_s > 0


def test_the_report_shows_the_person_as_a_system(session, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    run_dir = session[3]
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(run_dir), "--out", str(out), "--no-gallery"])
    assert result.exit_code == 0, result.output
    assert "human:alice" in (out / "report.html").read_text(encoding="utf-8")


def test_rescore_reads_a_persons_run_like_a_models(session):
    from typer.testing import CliRunner

    from povagent.cli import app

    run_dir = session[3]
    result = CliRunner().invoke(app, ["rescore", str(run_dir), "--parser", "json"])
    assert result.exit_code == 0, result.output
    rescored = list(iter_rows(run_dir / "rescored-json" / "results.jsonl"))
    assert [r.scores["official"]["l2"] for r in rescored] == [r.scores["official"]["l2"] for r in session[2]]
