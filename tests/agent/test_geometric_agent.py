"""GroundingAgent(strategy="geometric"): the robot's own cameras in, the solved 3D goal out.

A robot that knows its camera poses gets the target in its world directly (no back-projection
of a guessed pixel onto the floor). The model here is the queued backend answering the solver's
sub-questions with what a perfect perceiver would say about a generated house (the records'
boxes projected into the frames), so the goal must be the benchmark's ground truth.
"""

from __future__ import annotations

import json

import numpy as np

from povagent.agent import GroundingAgent
from povagent.dataset.loader import load_dataset
from povagent.geometry.placement import surface_kind
from povagent_plugins.backends.simulated import box_outline


def perfect_detections(instance, house, obj) -> str:
    centre = obj.raw_metadata.axisAlignedBoundingBox.center.as_tuple()
    found = []
    for i, (frame, record) in enumerate(zip(instance.frames, house.exploration)):
        u, v, depth = frame.camera.project_point(centre)
        if obj.objectId in record.object_in_frame_hits and depth > 0 and 0 <= u <= 1 and 0 <= v <= 1:
            found.append({"image": i, "x": u * 512, "y": v * 512, "box": list(box_outline(frame.camera, obj))})
    return json.dumps({"detections": found})


def well_seen_instance(dataset):
    """An Inferred instance whose anchor and observer are each seen in at least two frames."""
    for instance in dataset.instances(conditions=["a"]):
        house = dataset.houses[instance.house_id]
        seen = [sum(o.objectId in r.object_in_frame_hits for r in house.exploration) for o in (instance.anchor_object, instance.observer_object)]
        if min(seen) >= 3:
            return instance, house
    raise AssertionError("no well-seen instance in the generated set")


def test_the_agent_returns_the_solved_3d_goal_in_the_robots_world(generated_release, queued_backend):
    dataset = load_dataset(generated_release)
    instance, house = well_seen_instance(dataset)
    pair = house.pairs[instance.pair_id]
    queued_backend.queue(
        json.dumps({"observer": instance.observer_object.object_type, "anchor": instance.anchor_object.object_type, "direction": str(instance.direction)}),
        json.dumps({"surface": surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type)}),
        perfect_detections(instance, house, instance.anchor_object),
        perfect_detections(instance, house, instance.observer_object),
    )
    with GroundingAgent(backend="queued", strategy="geometric", parser="json") as agent:
        found = agent.locate(instance.sentence, [f.file for f in instance.frames], cameras=[f.camera for f in instance.frames])
    assert found.exchanges == 5 and found.goal is not None and found.goal.method == "geometry"
    assert np.linalg.norm(np.array(found.goal.point) - np.array(instance.target)) < 0.05
    assert "target_3d" in found.raw_answer


def test_when_the_solver_falls_back_its_pixel_is_back_projected_as_any_answer_is(generated_release, queued_backend):
    dataset = load_dataset(generated_release)
    instance, _house = well_seen_instance(dataset)
    queued_backend.queue('{"anchor": "kettle", "direction": "right"}', '{"surface": "floor"}', '{"detections": []}')
    with GroundingAgent(backend="queued", strategy="geometric", parser="json") as agent:
        found = agent.locate(instance.sentence, [f.file for f in instance.frames[:3]], cameras=[f.camera for f in instance.frames[:3]])
    assert "fallback: the anchor was not found in any frame" in found.raw_answer
    assert found.goal is not None and found.goal.method == "plane"  # no solved point: the floor under the pixel
    assert (found.frame_index, found.pixel) == (0, (256.0, 256.0))
