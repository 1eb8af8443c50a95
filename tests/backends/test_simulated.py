"""The perception simulator: answers from the records, noise as asked, never a model.

Its noise must be what its options say (the solver's benchmark reads off these knobs), its
answers must not depend on the order requests arrive in, and a request it cannot answer (any
free-form prompt) must be refused rather than answered with something model-like.
"""

from __future__ import annotations

import asyncio
import json
from dataclasses import replace

import numpy as np
import pytest

from povagent.dataset.loader import load_dataset
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.interfaces import PermanentBackendError
from povagent_plugins.backends.simulated import SimulatedPerception
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.geometric import GeometricStrategy


@pytest.fixture(scope="module")
def mini(mini_root):
    return load_dataset(mini_root)



def answer(backend, request) -> dict:
    response = asyncio.run(backend.complete(request, ImageStore()))
    assert response.model == "simulation"
    return json.loads(response.text)


def locate(instance, object_type="Sofa", role="anchor"):
    return GeometricStrategy().locate_request(instance, ImageStore(), object_type, role)


def detections_over_runs(backend, request, runs):
    return [answer(backend, replace(request, run=r))["detections"] for r in range(runs)]


SOFA_A = "train_house_00001/7/left/a"


def test_a_free_form_prompt_is_refused_as_a_simulation(mini):
    request = BasicStrategy().build(mini.instance(SOFA_A), ImageStore())
    with pytest.raises(PermanentBackendError, match=r"simulation, not a model.*strategy: geometric"):
        answer(SimulatedPerception(), request)


def test_without_noise_the_sofa_is_pointed_at_its_projected_box_centre(mini):
    instance = mini.instance(SOFA_A)
    found = answer(SimulatedPerception(), locate(instance))["detections"]
    assert [d["image"] for d in found] == [0, 1]  # both frames' records list Sofa|1
    centre = instance.anchor_object.raw_metadata.axisAlignedBoundingBox.center.as_tuple()
    for d in found:
        u, v, _ = instance.frames[d["image"]].camera.project_point(centre)
        assert (d["x"], d["y"]) == pytest.approx((u * 512, v * 512), abs=0.06)  # one decimal
        x0, y0, x1, y1 = d["box"]
        assert x0 <= d["x"] <= x1 and y0 <= d["y"] <= y1


def test_an_object_a_frame_record_does_not_list_is_not_reported_there(mini):
    found = answer(SimulatedPerception(), locate(mini.instance(SOFA_A), "Television", "observer"))["detections"]
    assert [d["image"] for d in found] == [1]


def test_pixel_noise_is_gaussian_with_the_sigma_asked(mini):
    instance = mini.instance(SOFA_A)
    exact = {d["image"]: (d["x"], d["y"]) for d in answer(SimulatedPerception(), locate(instance))["detections"]}
    noisy = SimulatedPerception(pixel_sigma=8.0, seed=1)
    errors = [
        (d["x"] - exact[d["image"]][0], d["y"] - exact[d["image"]][1])
        for found in detections_over_runs(noisy, locate(instance), 400)
        for d in found
        if 24 < exact[d["image"]][0] < 488 and 24 < exact[d["image"]][1] < 488  # clamping would bias
    ]
    e = np.array(errors)
    assert len(e) == 800
    assert np.abs(e.mean(axis=0)).max() < 1.0
    assert e.std(axis=0) == pytest.approx([8.0, 8.0], rel=0.1)


def test_each_frame_is_missed_at_the_rate_asked(mini):
    found = detections_over_runs(SimulatedPerception(miss_rate=0.3, seed=2), locate(mini.instance(SOFA_A)), 500)
    reported = sum(len(f) for f in found)
    assert reported / 1000 == pytest.approx(0.7, abs=0.05)


def test_answers_depend_on_seed_instance_run_and_question_only(mini):
    instance = mini.instance(SOFA_A)
    backend = SimulatedPerception(pixel_sigma=5.0, miss_rate=0.2, seed=3)
    first = [answer(backend, replace(locate(instance), run=r)) for r in range(5)]
    again = [answer(SimulatedPerception(pixel_sigma=5.0, miss_rate=0.2, seed=3), replace(locate(instance), run=r)) for r in reversed(range(5))]
    assert first == list(reversed(again))
    other_seed = [answer(SimulatedPerception(pixel_sigma=5.0, miss_rate=0.2, seed=4), replace(locate(instance), run=r)) for r in range(5)]
    assert other_seed != first


def test_the_surface_is_the_kind_of_the_records_stage3_surface(mini):
    strategy = GeometricStrategy()
    up = mini.instance("train_house_00000/0/up/a")  # stage3 up: "on the bed"
    front = mini.instance("train_house_00000/0/front/a")  # "on the floor"
    assert answer(SimulatedPerception(), strategy.surface_request(up, "Bed", "up")) == {"surface": "anchor"}
    assert answer(SimulatedPerception(), strategy.surface_request(front, "Bed", "front")) == {"surface": "floor"}


def test_a_wrong_surface_comes_at_the_rate_asked(mini):
    front = mini.instance("train_house_00000/0/front/a")
    request = GeometricStrategy().surface_request(front, "Bed", "front")
    backend = SimulatedPerception(wrong_surface_rate=0.25, seed=5)
    said = [answer(backend, replace(request, run=r))["surface"] for r in range(400)]
    assert sum(s != "floor" for s in said) / 400 == pytest.approx(0.25, abs=0.06)
    assert set(said) == {"floor", "anchor", "other"}


def test_the_read_answer_names_the_records_observer_anchor_and_direction(mini):
    instance = mini.instance(SOFA_A)
    read = answer(SimulatedPerception(), GeometricStrategy().read_request(instance))
    assert read == {"observer": "Television", "anchor": "Sofa", "direction": "left"}
    given = mini.instance("train_house_00001/7/left/c")
    assert answer(SimulatedPerception(), GeometricStrategy().read_request(given)) == {"anchor": "Sofa", "direction": "left"}


def test_wrong_furniture_comes_at_the_rate_asked_in_inferred_only(generated_release):
    dataset = load_dataset(generated_release)
    backend = SimulatedPerception(wrong_furniture_rate=0.4, seed=6)
    strategy = GeometricStrategy()
    wrong = {"a": 0, "b": 0}
    total = 0
    for instance in dataset.instances(conditions=["a", "b"]):
        for run in range(4):
            said = answer(backend, replace(strategy.read_request(instance), run=run))["observer"]
            wrong[str(instance.condition)] += said != instance.observer_object.object_type
            total += str(instance.condition) == "a"
    assert wrong["b"] == 0
    assert wrong["a"] / total == pytest.approx(0.4, abs=0.07)


def test_a_wrongly_read_furniture_is_pointed_at_where_it_stands(generated_release):
    dataset = load_dataset(generated_release)
    instance = dataset.instances(conditions=["a"])[0]
    house = dataset.houses[instance.house_id]
    pair = house.pairs[instance.pair_id]
    other = next(
        p.object_landmark for p in house.pairs.values()
        if p.landmark_type not in (pair.landmark_type, pair.object_observer.object_type)
    )
    found = answer(SimulatedPerception(), locate(instance, other.object_type, "observer"))["detections"]
    seen_in = {i for i, rec in enumerate(house.exploration) if other.objectId in rec.object_in_frame_hits}
    assert found and {d["image"] for d in found} <= seen_in


@pytest.mark.parametrize("option", ["miss_rate", "wrong_furniture_rate", "wrong_surface_rate"])
def test_a_rate_outside_0_1_is_a_config_error_naming_it(option):
    with pytest.raises(ConfigError, match=option):
        SimulatedPerception(**{option: 1.5})


def test_a_negative_sigma_is_a_config_error():
    with pytest.raises(ConfigError, match="pixel_sigma"):
        SimulatedPerception(pixel_sigma=-1)


def test_frames_outside_a_release_folder_need_the_dataset_option(mini, tmp_path):
    instance = mini.instance(SOFA_A)
    for f in instance.frames:
        (tmp_path / f.file.name).write_bytes(f.file.read_bytes())
    moved = replace(instance, frames=tuple(replace(f, file=tmp_path / f.file.name) for f in instance.frames))
    with pytest.raises(PermanentBackendError, match="dataset"):
        answer(SimulatedPerception(), locate(moved))
    assert answer(SimulatedPerception(dataset=str(mini.root)), locate(moved))["detections"]
