"""Placing the target from perceived estimates, on generated frames, against the GT rules.

With exact perception (each object's box centre pointed at in every frame whose record lists it,
its projected box as its outline) the solver's geometry must give the benchmark's own ground
truth: exactly where the anchor is triangulated, and within what the size prior gets wrong
where it is seen once. The placement reuses :func:`~povagent.geometry.ground_truth.target_point`,
so any drift between the two shows here.
"""

from __future__ import annotations

import numpy as np
import pytest

from povagent.dataset.loader import ground_truth_point
from povagent.geometry.camera import Camera
from povagent.geometry.placement import AnchorEstimate, choose_frame, place_target, surface_kind, surface_phrase
from povagent.geometry.size_priors import size_prior
from povagent.geometry.triangulation import Outline, Sighting, fit_box, locate, projected_box
from povagent.scoring.normalized_l2 import score_point


def exact_views(instance, house, obj):
    """Sightings and outlines of ``obj`` as a perfect perceiver reports them."""
    box = obj.raw_metadata.axisAlignedBoundingBox
    centre, half = np.array(box.center.as_tuple()), np.array(box.size.as_tuple()) / 2
    sightings, outlines = [], []
    for frame, record in zip(instance.frames, house.exploration):
        u, v, depth = frame.camera.project_point(centre)
        if obj.objectId not in record.object_in_frame_hits or not (depth > 0 and 0 <= u <= 1 and 0 <= v <= 1):
            continue
        sightings.append(Sighting(frame.camera, (u * 512, v * 512)))
        b = projected_box(frame.camera, centre, half)
        if b is not None:
            outlines.append(Outline(frame.camera, tuple(float(np.clip(b[k], 0, 511)) for k in range(4))))
    return sightings, outlines


def solve_exactly(instance, dataset):
    house = dataset.houses[instance.house_id]
    pair = house.pairs[instance.pair_id]
    anchor, observer = instance.anchor_object, instance.observer_object
    prior = size_prior(anchor.object_type)
    sightings, outlines = exact_views(instance, house, anchor)
    where = locate(sightings, prior.centre_height)
    box = fit_box(where.point, outlines, (prior.size[0] / 2, prior.half_height, prior.size[2] / 2), 0.05 if where.method == "triangulated" else 0.5)
    obs = locate(exact_views(instance, house, observer)[0], size_prior(observer.object_type).centre_height)
    kind = surface_kind(pair.stage3[instance.direction].surface, anchor.object_type)
    target = place_target(str(instance.direction), AnchorEstimate(box.centre, box.half), anchor.object_type, obs.point, kind)
    return where, obs, target


def test_exact_perception_gives_the_ground_truth_where_both_objects_are_triangulated(generated_dataset):
    checked = 0
    for instance in generated_dataset.instances(conditions=["a"]):
        where, obs, target = solve_exactly(instance, generated_dataset)
        if where.method == "triangulated" and obs.method == "triangulated":
            checked += 1
            assert np.linalg.norm(target - np.array(instance.target)) < 0.02, instance.id
    assert checked >= 10


def test_an_anchor_seen_once_is_off_only_along_its_ray_by_the_height_prior(generated_dataset):
    for instance in generated_dataset.instances(conditions=["a"]):
        where, _, _ = solve_exactly(instance, generated_dataset)
        if where.method != "height prior":
            continue
        prior = size_prior(instance.anchor_object.object_type)
        assert where.point[1] == pytest.approx(prior.centre_height)


def test_exact_perception_scores_near_zero_in_the_chosen_frames(generated_dataset):
    errors = []
    for instance in generated_dataset.instances(conditions=["a", "b"]):
        _, _, target = solve_exactly(instance, generated_dataset)
        choice = choose_frame(target, [f.camera for f in instance.frames])
        errors.append(score_point(instance, instance.frames[choice.index], *choice.pixel).l2_strict)
    assert np.mean(errors) < 0.03 and np.median(errors) < 0.005


@pytest.mark.parametrize(
    ("surface", "anchor", "kind"),
    [
        ("on the floor", "Bed", "floor"),
        ("on the floor next to the bed", "Bed", "floor"),  # floor is tested first, as the GT does
        ("on the bed", "Bed", "anchor"),
        ("on the couch", "Sofa", "anchor"),
        ("on the kitchen counter", "CounterTop", "anchor"),
        ("on the dresser", "Bed", "other"),
        (None, "Bed", "other"),
    ],
)
def test_a_release_surface_phrase_has_one_kind(surface, anchor, kind):
    assert surface_kind(surface, anchor) == kind


@pytest.mark.parametrize("kind", ["floor", "anchor", "other"])
def test_the_phrase_of_a_kind_reads_back_as_that_kind(kind):
    assert surface_kind(surface_phrase(kind, "SideTable"), "SideTable") == kind


def test_placement_is_the_ground_truth_rule_given_the_true_anchor_and_observer(generated_dataset):
    for instance in generated_dataset.instances(conditions=["a"]):
        pair = generated_dataset.houses[instance.house_id].pairs[instance.pair_id]
        box = pair.object_landmark.raw_metadata.axisAlignedBoundingBox
        anchor = AnchorEstimate(box.center.as_tuple(), tuple(v / 2 for v in box.size.as_tuple()))
        # the release's top is the corners' highest y: centre + half height, up to its rounding
        kind = surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type)
        placed = place_target(str(instance.direction), anchor, pair.landmark_type, pair.camera.cam_pos, kind)
        assert np.allclose(placed, ground_truth_point(pair, instance.direction), atol=1e-3), instance.id


def test_the_frame_chosen_shows_the_target_nearest_the_centre():
    target = (0.0, 0.5, 3.0)
    off_centre = Camera.from_pose((1.0, 0.9, 0.0), 0.0, 30.0)
    centred = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 10.0)
    away = Camera.from_pose((0.0, 0.9, 0.0), 180.0, 30.0)
    choice = choose_frame(target, [away, off_centre, centred])
    assert choice.index == 2 and choice.placement == "in frame"


def test_a_target_behind_every_camera_gets_the_centre_of_the_one_facing_it_most():
    target = (0.0, 0.5, -3.0)
    backwards = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 30.0)  # looks at +z, target straight behind
    sideways = Camera.from_pose((0.0, 0.9, 0.0), 80.0, 0.0)  # looks nearly along +x: the target is behind, aside
    choice = choose_frame(target, [backwards, sideways])
    assert (choice.index, choice.pixel, choice.placement) == (1, (256.0, 256.0), "behind every camera")


def test_a_target_in_front_but_outside_every_image_is_clamped_to_the_border():
    cam = Camera.from_pose((0.0, 0.9, 0.0), 0.0, 0.0)
    choice = choose_frame((10.0, 0.9, 1.0), [cam])  # far to the right, in front
    assert choice.placement == "in front, outside the frame" and choice.pixel[0] == 511.0
