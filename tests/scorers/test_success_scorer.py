"""The ``success`` scorer, and a real-world set run by the runner like any dataset."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path

import pytest

from povagent.answers.spec import ParsedAnswer, ParseStatus, unparseable
from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.dataset.realworld_set import load_realworld, success_breakdown
from povagent.errors import ConfigError
from povagent.results.rows import iter_rows
from povagent.run.runner import PipelineRun
from povagent.testing.loopback_server import LoopbackServer
from povagent_plugins.scorers.success import SuccessScorer, inside_polygon

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"
KEY_ENV = "POVAGENT_REALWORLD_TEST_KEY"


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    return load_realworld(DEMO, cache_dir=tmp_path_factory.mktemp("letterboxed"))


def answer(x: float, y: float, frame: int | None = None) -> ParsedAnswer:
    return ParsedAnswer(status=ParseStatus.OK, selected_image=frame, x=x, y=y)


def square(x: float, y: float) -> tuple[float, float]:
    """A 1280x720 original pixel in the letterboxed square."""
    return (x * 0.4, y * 0.4 + 112)


def test_an_answer_on_the_marked_point_is_a_hit(demo):
    score = SuccessScorer().score(demo.instance("house_1/kitchen/right/a"), answer(*square(540, 310), frame=1))
    assert score["success"] and score["answered"] and score["frame_has_gt"]
    assert score["pixel"] == pytest.approx([540, 310]) and score["distance_px"] == pytest.approx(0, abs=1e-9)


def test_the_default_radius_is_a_tenth_of_the_diagonal(demo):
    inst = demo.instance("house_1/kitchen/right/a")
    radius = 0.1 * (1280**2 + 720**2) ** 0.5  # 146.9 px
    near = SuccessScorer().score(inst, answer(*square(540 + radius - 1, 310), frame=1))
    far = SuccessScorer().score(inst, answer(*square(540 + radius + 1, 310), frame=1))
    assert near["success"] and not far["success"]
    assert far["distance_norm"] == pytest.approx((radius + 1) / (1280**2 + 720**2) ** 0.5)


def test_radius_px_option_overrides_the_default(demo):
    inst = demo.instance("house_1/kitchen/right/a")
    assert not SuccessScorer(radius_px=10).score(inst, answer(*square(560, 310), frame=1))["success"]


def test_a_marks_own_radius_wins(demo):
    inst = demo.instance("house_1/bedroom/up/c")  # point (970, 425) with radius_px 60
    assert SuccessScorer(radius_px=1).score(inst, answer(*square(1025, 425)))["success"]
    assert not SuccessScorer(radius_px=1000).score(inst, answer(*square(1035, 425)))["success"]


def test_the_right_point_in_a_frame_without_marks_is_a_miss(demo):
    score = SuccessScorer().score(demo.instance("house_1/kitchen/right/a"), answer(*square(540, 310), frame=0))
    assert not score["success"] and score["answered"] and score["frame_has_gt"] is False


def test_box_marks_hit_inside_only(demo):
    inst = demo.instance("house_1/kitchen/right/c")  # box 490..600 x 270..340
    assert SuccessScorer().score(inst, answer(*square(495, 275)))["success"]
    assert not SuccessScorer().score(inst, answer(*square(610, 300)))["success"]


def test_region_marks_hit_inside_only(demo):
    inst = demo.instance("house_1/bedroom/up/a")  # polygon 900..1040 x 410..450 in frame 2
    assert SuccessScorer().score(inst, answer(*square(950, 430), frame=2))["success"]
    assert not SuccessScorer().score(inst, answer(*square(950, 470), frame=2))["success"]


def test_answers_in_a_portrait_frame_are_mapped_through_its_letterbox(demo):
    inst = demo.instance("house_1/study/front/a")  # frame 3 is 480x640: scale 0.8, offset x 64
    score = SuccessScorer(radius_px=2).score(inst, answer(240 * 0.8 + 64, 615 * 0.8, frame=3))
    assert score["success"] and score["pixel"] == pytest.approx([240, 615])


def test_unparseable_and_frameless_answers_are_failures(demo):
    inst = demo.instance("house_1/kitchen/right/a")
    assert SuccessScorer().score(inst, unparseable("no json")) == {
        "answered": False, "success": False, "frame_has_gt": None, "pixel": None, "distance_px": None, "distance_norm": None,
        "hit_radius_px": None,
    }
    assert not SuccessScorer().score(inst, answer(*square(540, 310), frame=None))["answered"]


def test_release_instances_are_refused_with_a_pointer_to_official(mini_dataset):
    inst = mini_dataset.instances()[0]
    with pytest.raises(ValueError, match="score it with 'official'"):
        SuccessScorer().score(inst, answer(1, 1, 0))


@pytest.mark.parametrize("radius", [0, -1, True, "big"])
def test_bad_radius_options_are_rejected(radius):
    with pytest.raises(ValueError, match="radius"):
        SuccessScorer(radius=radius)


def test_polygon_edges_count_as_inside():
    square_poly = [(0, 0), (10, 0), (10, 10), (0, 10)]
    assert inside_polygon(10, 5, square_poly) and inside_polygon(0, 0, square_poly)
    assert inside_polygon(5, 5, square_poly) and not inside_polygon(10.01, 5, square_poly)
    concave = [(0, 0), (10, 0), (10, 10), (5, 3), (0, 10)]
    assert not inside_polygon(5, 8, concave) and inside_polygon(5, 2, concave)


def test_the_runner_runs_a_real_world_set_and_rows_carry_success(tmp_path, monkeypatch, demo):
    # a "model" that always points at the phone's spot in frame 1 (the kitchen counter)
    reply = json.dumps({"selected_image": 1, "x": 540 * 0.4, "y": 310 * 0.4 + 112})
    monkeypatch.setenv(KEY_ENV, "test-key")
    with LoopbackServer(reply=reply, max_lifetime_s=60) as server:
        config = pipeline_from_source(ConfigSource("<test>", {
            "dataset": {"path": str(DEMO)},
            "backend": {"name": "litellm", "options": {"model": "openai/loopback", "api_base": server.url, "api_key_env": KEY_ENV}},
            "scorers": ["success"],
            "cache": False,
            "output": str(tmp_path / "run"),
        }, {}))
        result = asyncio.run(PipelineRun(config, dataset=demo).run())
    rows = list(iter_rows(tmp_path / "run" / "results.jsonl"))
    assert result.summary.rows.answered == 6
    hits = {r.instance_id: r.scores["success"]["success"] for r in rows}
    assert hits == {
        "house_1/kitchen/right/a": True, "house_1/kitchen/right/b": True, "house_1/kitchen/right/c": True,
        "house_1/bedroom/up/a": False, "house_1/bedroom/up/c": False, "house_1/study/front/a": False,
    }
    table = success_breakdown({"condition": r.condition, "direction": r.direction, **r.scores["success"]} for r in rows)
    assert table["overall"]["success_rate"] == 0.5 and table["per_condition"]["c"]["success_rate"] == 0.5


def test_the_official_metric_on_a_real_world_set_is_refused_before_any_request(tmp_path, demo):
    # its 2D marks leave the 3D target NaN, which the official rules would score a centre guess 0
    config = pipeline_from_source(ConfigSource("<test>", {
        "dataset": {"path": str(DEMO)}, "backend": "center", "scorers": ["official"], "output": str(tmp_path / "run"),
    }, {}))
    with pytest.raises(ConfigError, match=r"official needs 3D ground truth.*scorers: \[success\]"):
        asyncio.run(PipelineRun(config, dataset=demo).run())
    assert not (tmp_path / "run" / "results.jsonl").exists()


def test_a_third_party_scorer_declaring_it_needs_a_3d_target_is_refused_by_a_real_world_set(demo):
    from povagent.interfaces import Scorer

    class DepthScorer(Scorer):
        needs_3d_target = True

        def score(self, instance, answer, dataset=None):
            return {}

    with pytest.raises(ConfigError, match=r"scorer depth needs 3D ground truth.*scorers: \[success\]"):
        demo.check_scorers({"depth": DepthScorer, "success": SuccessScorer})
    demo.check_scorers({"success": SuccessScorer})  # hand-marked ground truth is what it reads


def test_povagent_run_runs_the_demo_pipeline_and_prints_success_rates(tmp_path):
    # from the repository root, as the README says (the pipeline names its set relative to it)
    done = subprocess.run(
        [sys.executable, "-m", "povagent.cli", "run", "examples/realworld_demo/pipeline.yaml", "-o", str(tmp_path / "run"), "-q"],
        capture_output=True, text=True, cwd=DEMO.parents[1], timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "success rate (unanswered = failure)" in done.stdout
    assert "mean L2" not in done.stdout  # no official table of zeros beside it
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["success"]["overall"]["n_total"] == 6 and summary["rows"]["answered"] == 6
