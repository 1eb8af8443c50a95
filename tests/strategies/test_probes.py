"""The perception probes ``probe-anchor`` and ``probe-observer``, through the real runner.

On the session's generated set, the ``planted`` simulation answers turn 1 (the basic question)
with its planted behaviour and the probe with perfect perception (the object's centre as the
official rules place a point, plus 5 px of noise), so every pointing error is the noise; the
queued backend gives the answers a test needs to shape.
"""

from __future__ import annotations

import asyncio
import json

import pytest

from povagent.config.pipeline import ConfigSource, pipeline_from_source
from povagent.exchange.images import ImageStore
from povagent.results.rows import RowStatus, iter_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import PipelineRun
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.probes import AnchorProbe, ObserverProbe


def probe_run(dataset, out, strategy: str, conditions=("a", "b", "c"), backend=None, scorers=None, **selection) -> list:
    config = pipeline_from_source(ConfigSource("<test>", {
        "dataset": {"path": str(dataset)}, "instances": {"conditions": list(conditions), **selection},
        "backend": backend or {"name": "planted", "options": {"random_frame": 0.3, "pixel_sigma": 5, "seed": 0}},
        "strategy": strategy, "parser": "official", "scorers": scorers or [strategy], "cache": False, "output": str(out),
    }, {}))  # fmt: skip
    asyncio.run(PipelineRun(config).run())
    return list(iter_rows(out / "results.jsonl"))


@pytest.fixture(scope="module")
def anchor_run(generated_release, tmp_path_factory):
    """(run folder, rows) of probe-anchor on every instance, answered by the planted simulation."""
    out = tmp_path_factory.mktemp("probe") / "anchor"
    return out, probe_run(generated_release, out, "probe-anchor")


@pytest.fixture(scope="module")
def anchor_rows(anchor_run):
    return anchor_run[1]


def test_the_probe_is_asked_in_the_frame_turn_1_selected(anchor_rows):
    frames = [r for r in anchor_rows if r.condition != "c"]
    assert frames
    for row in frames:
        chosen = json.loads(row.exchanges[0].raw)["selected_image"]
        assert len(row.exchanges) == 3 and row.prediction.selected_image == chosen
        assert row.exchanges[1].image_hashes == [row.exchanges[0].image_hashes[chosen]]  # that frame alone
        assert "Point at the" in row.exchanges[1].prompt


def test_a_perfect_perceiver_points_within_its_noise_wherever_the_anchor_is_in_view(anchor_rows):
    scored = [r.scores["probe-anchor"] for r in anchor_rows if r.status == RowStatus.ANSWERED]
    assert len(scored) == len(anchor_rows)
    in_view = [s for s in scored if s["in_view"] and s["seen"]]
    assert len(in_view) > 50
    # 5 px of noise per axis on a 512 px frame: 4 sigma is 0.055 of the frame
    assert all(s["centre_error"] < 0.056 for s in in_view)
    assert sum(s["inside_box"] for s in in_view) / len(in_view) > 0.95


def test_frames_without_the_anchor_are_recorded_as_such(anchor_rows):
    # the planted random-frame behaviour picks a frame that does not show the anchor
    assert any(not r.scores["probe-anchor"]["seen"] for r in anchor_rows if r.condition != "c")
    assert all(r.scores["probe-anchor"]["seen"] for r in anchor_rows if r.condition == "c")


def test_given_asks_the_one_question_about_the_observer_view(anchor_rows):
    given = [r for r in anchor_rows if r.condition == "c"]
    assert given and all(len(r.exchanges) == 1 and set(json.loads(r.raw_response)) == {"x", "y"} for r in given)


def test_turn_1_is_the_basic_strategys_own_request(generated_release):
    from povagent.dataset.loader import load_dataset

    inst = load_dataset(generated_release, check_images=False).instances(conditions=["a"])[0]
    images = ImageStore()
    assert AnchorProbe().build(inst, images).content_hash() == BasicStrategy().build(inst, images).content_hash()


def test_the_observer_probe_points_at_the_observer_and_refuses_given(generated_release, tmp_path):
    rows = probe_run(generated_release, tmp_path / "observer", "probe-observer")
    frames = [r for r in rows if r.condition != "c"]
    assert frames and all(r.status == RowStatus.ANSWERED and r.scores["probe-observer"]["object_type"] for r in frames)
    seen = [r.scores["probe-observer"] for r in frames if r.scores["probe-observer"]["in_view"] and r.scores["probe-observer"]["seen"]]
    assert seen and all(s["centre_error"] < 0.056 for s in seen)
    given = [r for r in rows if r.condition == "c"]
    assert given and all(r.status == RowStatus.INFRA_ERROR and "conditions: [a, b]" in r.error_message for r in given)


def test_without_a_frame_from_turn_1_the_probe_is_not_asked(mini_root, tmp_path, queued_backend):
    queued_backend.queue("I cannot tell which image.")
    rows = probe_run(mini_root, tmp_path / "noframe", "probe-anchor", conditions=("a",), backend={"name": "queued"},
                     directions=["right"], houses=["train_house_00000"])
    (row,) = rows
    assert len(queued_backend.requests) == 1  # turn 2 never sent
    assert row.status == RowStatus.PARSE_ERROR and "the probe was not asked" in row.raw_response


def test_rescoring_a_probe_run_reads_the_same_answers(anchor_run):
    run, anchor_rows = anchor_run
    result = rescore_run(run)
    rescored = {r.key: r for r in iter_rows(result.out_dir / "results.jsonl")}
    for row in anchor_rows:
        assert rescored[row.key].scores["probe-anchor"] == row.scores["probe-anchor"], row.key
        assert rescored[row.key].prediction == row.prediction


def test_the_planned_turns_show_the_probe_and_the_worked_out_answer(generated_release):
    from povagent.dataset.loader import load_dataset

    ds = load_dataset(generated_release, check_images=False)
    turns = ObserverProbe().plan_turns(ds.instances(conditions=["b"])[0], ImageStore())
    assert [t.sent for t in turns] == [True, True, False]
    assert turns[1].request.question["kind"] == "probe" and "selected_image" in turns[1].note
    assert len(AnchorProbe().plan_turns(ds.instances(conditions=["c"])[0], ImageStore())) == 1
