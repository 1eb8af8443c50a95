"""The ``planted`` behaviour simulation, and the diagnostics recovering what it planted.

The recoveries run on the session's 2-house generated set (39 instances per condition) with
several runs (each run draws the behaviours afresh). The issue's check, a 40% egocentric model
measured at 0.40 +- 0.05 on a 10-house set, takes minutes to generate and lives in
``benchmarks/planted_recovery.py``; here the nominal check's tolerance is three binomial
standard errors of the number of eligible answers, and the exact check compares each eligible
answer's vote with the behaviour actually drawn for it.
"""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path

import pytest

from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.dataset.loader import load_dataset
from povagent.errors import ConfigError
from povagent.results.rows import iter_rows
from povagent.run.runner import PipelineRun
from povagent_plugins.backends.planted import PlantedBehaviour

RUNS = 6


def planted_run(dataset: Path, out: Path, runs: int = RUNS, strategy: str = "basic", **options) -> tuple[dict, list]:
    config = pipeline_from_source(ConfigSource("<test>", {
        "dataset": {"path": str(dataset)}, "backend": {"name": "planted", "options": {"pixel_sigma": 5, "seed": 0, **options}},
        "strategy": strategy, "parser": "official", "scorers": ["official", "diagnose", "relation"], "runs": runs,
        "cache": False, "output": str(out),
    }, {}))  # fmt: skip
    asyncio.run(PipelineRun(config).run())
    return json.loads((out / "summary.json").read_text()), list(iter_rows(out / "results.jsonl"))


@pytest.fixture(scope="module")
def egocentric_40(generated_release, tmp_path_factory):
    return planted_run(generated_release, tmp_path_factory.mktemp("planted") / "ego40", egocentric=0.4)


@pytest.fixture(scope="module")
def all_zero(generated_release, tmp_path_factory):
    return planted_run(generated_release, tmp_path_factory.mktemp("planted") / "zero", runs=2)


def test_a_40_percent_egocentric_model_has_a_bias_index_of_0_40(egocentric_40):
    summary, _ = egocentric_40
    for cond in ("a", "b"):
        cell = summary["diagnostics"]["per_condition"][cond]
        n = cell["bias_n"]
        tolerance = 3 * math.sqrt(0.4 * 0.6 / n)
        assert n >= 60 and abs(cell["egocentric_bias"] - 0.40) <= tolerance, (cond, cell["egocentric_bias"], n)
        lo, hi = cell["egocentric_bias_ci"]
        assert lo < cell["egocentric_bias"] < hi


def test_each_eligible_vote_matches_the_behaviour_drawn(egocentric_40, generated_release):
    _, rows = egocentric_40
    dataset = load_dataset(generated_release, check_images=False)
    backend = PlantedBehaviour(egocentric=0.4, pixel_sigma=5, seed=0)
    votes = [(r.scores["diagnose"]["nearer_egocentric"], backend.behaviour(dataset.instance(r.instance_id), r.run))
             for r in rows if r.scores["diagnose"].get("bias_eligible")]  # fmt: skip
    agree = sum(vote == (drawn == "egocentric") for vote, drawn in votes)
    assert len(votes) >= 120 and agree / len(votes) >= 0.98


def test_egocentric_answers_where_the_targets_differ_are_viewpoint_failures(egocentric_40, generated_release):
    _, rows = egocentric_40
    dataset = load_dataset(generated_release, check_images=False)
    backend = PlantedBehaviour(egocentric=0.4)
    steps = [r.scores["diagnose"]["step"] for r in rows
             if r.scores["diagnose"].get("bias_eligible") and backend.behaviour(dataset.instance(r.instance_id), r.run) == "egocentric"]
    assert steps and steps.count("viewpoint") / len(steps) >= 0.95


def test_a_planted_model_answering_the_truth_has_no_viewpoint_failures(all_zero):
    summary, rows = all_zero
    for cond, cell in summary["diagnostics"]["per_condition"].items():
        assert cell["failure_steps"]["viewpoint"] == 0.0, cond
        assert cell["relation_success"] >= 0.99, cond
    assert sum(1 for r in rows if r.scores["relation"]["success"]) / len(rows) >= 0.99


def test_given_has_no_bias_index(all_zero):
    cell = all_zero[0]["diagnostics"]["per_condition"]["c"]
    assert cell["egocentric_bias"] is None and cell["bias_n"] == 0 and "observer view is the camera" in cell["egocentric_bias_note"]


def test_random_frame_answers_fail_at_the_frame_step(generated_release, tmp_path):
    summary, _ = planted_run(generated_release, tmp_path / "rf", runs=1, random_frame=1.0)
    for cond in ("a", "b"):
        # every instance of this set has frames without its anchor, so each answer picks one
        assert summary["diagnostics"]["per_condition"][cond]["failure_steps"]["frame"] == 1.0


def test_mirrored_left_right_answers_are_viewpoint_failures_in_given(generated_release, tmp_path):
    _, rows = planted_run(generated_release, tmp_path / "mirror", runs=1, mirror=1.0)
    lateral = [r.scores["diagnose"] for r in rows if r.condition == "c" and r.direction in ("left", "right")
               and math.dist(r.scores["diagnose"]["mirrored"], [r.scores["official"]["gt_u"], r.scores["official"]["gt_v"]]) > 0.05]
    assert lateral and all(d["step"] == "viewpoint" for d in lateral)


def test_answers_follow_the_strategy_format_and_say_they_are_a_simulation(generated_release, tmp_path):
    _, rows = planted_run(generated_release, tmp_path / "cot", runs=1, strategy="cot", egocentric=0.5)
    by_cond = {r.condition: r for r in rows}
    assert set(json.loads(by_cond["a"].raw_response)) == {"selected_image", "x", "y"}
    assert set(json.loads(by_cond["c"].raw_response)) == {"x", "y"}
    assert all(r.status == "answered" for r in rows)


@pytest.mark.parametrize("options", [{"egocentric": 1.5}, {"mirror": -0.1}, {"egocentric": 0.6, "mirror": 0.6},
                                     {"pixel_sigma": -1}, {"seed": "zero"}, {"random_frame": True}])
def test_bad_options_are_refused(options):
    with pytest.raises(ConfigError, match="planted"):
        PlantedBehaviour(**options)


def test_the_identity_says_simulation():
    assert PlantedBehaviour(egocentric=0.4).identity()["simulation"] is True
