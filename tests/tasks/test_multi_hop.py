"""The multi-hop task: the relation reached through an intermediate object, its ground truth
checked against the generated house's geometry by a computation of its own here."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

import numpy as np
import pytest

from povagent.config.models import PipelineConfig, TaskSpec
from povagent.dataset.loader import load_dataset
from povagent.generate.floorplan import generate_floorplan
from povagent.generate.furnishing import furnish
from povagent.generate.house_pipeline import house_generators
from povagent.geometry.directions import spec_of
from povagent.tasks.multi_hop import find_hop, house_scene
from povagent.tasks.task_set import for_task

#: The seed tests/conftest.py generates ``generated_release`` with.
SEED = 3


@pytest.fixture(scope="module")
def point_set(generated_release):
    return load_dataset(generated_release, check_images=False)


@pytest.fixture(scope="module")
def choice_set(point_set):
    return for_task(point_set, TaskSpec(name="multi-hop", answer="choice"))


@pytest.fixture(scope="module")
def point_hop_set(point_set):
    return for_task(point_set, TaskSpec(name="multi-hop"))


@functools.cache
def _objects(house_id: str) -> dict[str, object]:
    """The house's furniture by objectId, planned and furnished here from the seed."""
    rngs = house_generators(SEED, int(house_id.rsplit("_", 1)[1]))
    plan = generate_floorplan(rngs["plan"])
    return {o.object_id: o for o in furnish(plan, rngs["furnish"])}


@functools.cache
def _scene(root: Path, house_id: str):
    """The house as the task rebuilds it (once a house)."""
    return house_scene(root, house_id)


def _pair(generated_release, house_id: str, pair_id: str) -> dict:
    pairs = json.loads((generated_release / "artifacts" / house_id / f"{house_id}.json").read_text())
    return next(p for p in pairs if str(p["pair_id"]) == pair_id)


def _speaker_axes(pair: dict) -> tuple[np.ndarray, np.ndarray]:
    """(right, forward) on the floor as the speaker faces the anchor (x, z)."""
    anchor, cam = pair["object_landmark"]["position"], pair["camera"]["cam_pos"]
    fx, fz = anchor["x"] - cam[0], anchor["z"] - cam[2]
    norm = math.hypot(fx, fz)
    forward = np.array([fx / norm, fz / norm])
    return np.array([forward[1], -forward[0]]), forward


def _along(obj, axis: np.ndarray) -> tuple[float, float]:
    """The object's footprint as an interval along ``axis`` (from its corners)."""
    (cx, _, cz), (sx, _, sz) = obj.center, obj.size
    values = [float(np.dot((cx + dx * sx / 2, cz + dz * sz / 2), axis)) for dx in (-1, 1) for dz in (-1, 1)]
    return min(values), max(values)


def _expected(target, obj, right, forward) -> str | None:
    """Where ``target`` is from ``obj`` as the speaker sees it, worked out from the corners."""
    point = np.array([target[0], target[2]])
    lo, hi = _along(obj, right)
    s = float(point @ right)
    if s > hi:
        return "right"
    if s < lo:
        return "left"
    near, _far = _along(obj, forward)
    if float(point @ forward) < near:
        return "front"
    return "up" if target[1] > obj.center[1] + obj.local_size[1] / 2 else None


def test_the_generated_set_has_multi_hop_instances_in_every_condition(choice_set, point_hop_set):
    assert {i.condition.value for i in choice_set.instances()} == {"a", "b", "c"}
    assert [i.id for i in choice_set.instances()] == [i.id for i in point_hop_set.instances()]


def test_the_gold_is_where_the_target_stands_from_the_intermediate_in_the_speakers_view(choice_set, generated_release):
    checked = 0
    for inst in choice_set.instances():
        objects = _objects(inst.house_id)
        hop = find_hop(inst, _scene(generated_release, inst.house_id))
        pair = _pair(generated_release, inst.house_id, inst.pair_id)
        right, forward = _speaker_axes(pair)
        expected = _expected(inst.target, objects[hop.intermediate.object_id], right, forward)
        assert expected is not None and dict(inst.question.options)[inst.question.gold] == spec_of(expected).short_words, inst.id
        checked += 1
    assert checked >= 3


def test_the_stated_hop_holds_in_the_geometry(choice_set, generated_release):
    for inst in choice_set.instances():
        objects = _objects(inst.house_id)
        hop = find_hop(inst, _scene(generated_release, inst.house_id))
        pair = _pair(generated_release, inst.house_id, inst.pair_id)
        anchor, middle = objects[pair["object_landmark"]["objectId"]], objects[hop.intermediate.object_id]
        right, _ = _speaker_axes(pair)
        stated = f"the {hop.name} was {spec_of(hop.link).sentence_phrase.split('{anchor}')[0]}"
        said = inst.question.question
        if hop.link == "up":
            assert middle.support == anchor.object_id and f"the {hop.name} was on" in said
        elif hop.link == "left":
            assert _along(middle, right)[1] < _along(anchor, right)[0] and stated in said
        else:
            assert _along(middle, right)[0] > _along(anchor, right)[1] and stated in said


def test_the_question_asks_the_target_relative_to_the_intermediate(choice_set, generated_release):
    for inst in choice_set.instances():
        hop = find_hop(inst, _scene(generated_release, inst.house_id))
        assert inst.question.question.endswith(f"relative to the {hop.name}?") and inst.question.category == hop.gold


def test_the_point_answer_keeps_the_point_tasks_ground_truth_and_names_the_anchor_through_the_intermediate(point_hop_set, point_set, generated_release):
    for inst in point_hop_set.instances():
        point = point_set.instance(inst.id)
        hop = find_hop(inst, _scene(generated_release, inst.house_id))
        assert inst.question is None and inst.target == point.target
        assert inst.sentence.startswith(point.sentence[:-1] + " that ") and f"the {hop.name}" in inst.sentence


def test_the_oracle_answers_every_multi_hop_choice_correctly(task_pipeline, run_rows):
    rows = run_rows(task_pipeline({"name": "multi-hop", "answer": "choice"}, "oracle"))
    assert rows and all(r["scores"]["choice"]["correct"] for r in rows)


def test_the_point_answer_is_scored_by_the_official_metric(task_pipeline, run_rows):
    rows = run_rows(task_pipeline("multi-hop", "oracle", strategy="basic", scorers=["official"]))
    assert rows and all(r["scores"]["official"]["l2"] < 0.01 for r in rows if r["scores"]["official"]["answered"])


def test_the_relation_task_is_never_answered_as_a_point():
    with pytest.raises(ValueError, match="task relation is answered as choice, not point"):
        PipelineConfig.model_validate({"dataset": "x", "backend": {"name": "oracle"}, "output": "o", "task": {"name": "relation", "answer": "point"}})
