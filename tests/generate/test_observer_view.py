"""The observer view plainly shows the anchor and looks at its centre from 1.55 m."""

from __future__ import annotations

import numpy as np

from povagent.dataset.release_models import PairEntry
from povagent.generate.pairs import (
    BODY_RADIUS,
    MIN_ANCHOR_PIXELS,
    MIN_ANCHOR_VISIBLE_FRACTION,
    SEATS,
    centre_unoccluded,
    shows_anchor,
)
from povagent.geometry.camera import Camera


def _index(tiny_dataset, object_id: str) -> int:
    """The anchor's index in ``house.objects`` (its instance id is this + 1)."""
    return next(k for k, o in enumerate(tiny_dataset.built.house.objects) if o.object_id == object_id)


def _entries(tiny_dataset) -> list[PairEntry]:
    entries = [PairEntry.model_validate(e) for e in tiny_dataset.pairs()]
    assert entries, "the tiny house should yield pairs"
    return entries


def _camera(entry: PairEntry) -> Camera:
    return Camera.from_pose(entry.camera.cam_pos, entry.camera.cam_yaw, entry.camera.cam_horizon)


def test_the_observer_view_shows_most_of_the_anchor_by_its_instance_mask(tiny_dataset):
    renderer = tiny_dataset.built.renderer
    for entry in _entries(tiny_dataset):
        k = _index(tiny_dataset, entry.object_landmark.objectId)
        shown = int(np.sum(tiny_dataset.instance(str(entry.pair_id)) == k + 1))
        whole = int(np.sum(renderer.silhouette(_camera(entry), k)))
        assert shown >= MIN_ANCHOR_PIXELS, entry.pair_id
        assert shown >= MIN_ANCHOR_VISIBLE_FRACTION * whole, (entry.pair_id, shown, whole)


def test_nothing_stands_between_the_observer_and_the_anchor_centre(tiny_dataset):
    house, renderer = tiny_dataset.built.house, tiny_dataset.built.renderer
    for entry in _entries(tiny_dataset):
        k = _index(tiny_dataset, entry.object_landmark.objectId)
        assert centre_unoccluded(renderer, _camera(entry), house.objects[k], k), entry.pair_id


def test_an_anchor_seen_through_a_wall_does_not_count_as_shown(tiny_dataset):
    house, renderer = tiny_dataset.built.house, tiny_dataset.built.renderer
    k = _index(tiny_dataset, _entries(tiny_dataset)[0].object_landmark.objectId)
    anchor = house.objects[k]
    # a camera outside the house, looking at the anchor through the exterior wall
    fp = house.plan.footprint
    x, z = fp.x0 - 1.0, anchor.center[2]
    yaw = float(np.degrees(np.arctan2(anchor.center[0] - x, anchor.center[2] - z)))
    horizon = float(np.degrees(np.arctan2(1.55 - anchor.center[1], anchor.center[0] - x)))
    outside = Camera((x, 1.55, z), yaw, horizon)
    assert renderer.silhouette(outside, k).sum() > 0  # it would be in view...
    assert not centre_unoccluded(renderer, outside, anchor, k)  # ...but the wall hides it
    shown = renderer.instance_mask(outside) == k + 1
    assert not shows_anchor(shown, renderer.silhouette(outside, k))


def test_a_partly_hidden_anchor_needs_most_of_its_silhouette_in_view():
    whole = np.zeros((64, 64), dtype=bool)
    whole[:40, :40] = True  # 1600 pixels unoccluded
    half = whole.copy()
    half[:, 20:] = False  # 800 of them left: half hidden
    most = whole.copy()
    most[:, 36:] = False  # 1440 left
    assert shows_anchor(most, whole)
    assert not shows_anchor(half, whole)


def test_a_tiny_anchor_is_not_shown_even_when_nothing_hides_it():
    speck = np.zeros((512, 512), dtype=bool)
    speck[:20, :20] = True  # 400 pixels, all of its silhouette
    assert not shows_anchor(speck, speck)


def test_a_standing_observer_stands_on_free_floor(tiny_dataset):
    house = tiny_dataset.built.house
    checked = 0
    for entry in _entries(tiny_dataset):
        observer = house.by_id(entry.object_observer.objectId)
        if observer.object_type in SEATS:
            continue
        x, _, z = entry.camera.cam_pos
        lo, hi = np.array([x - BODY_RADIUS, 0.05, z - BODY_RADIUS]), np.array([x + BODY_RADIUS, 1.7, z + BODY_RADIUS])
        for o in house.objects:
            if o.object_type == "Doorway" and "entrance" not in o.flags:
                continue  # a person may stand in an open doorway
            assert not o.box_overlaps(lo, hi, tolerance=0.0), (entry.pair_id, o.object_id)
        checked += 1
    assert checked > 0


def test_the_observer_camera_is_at_eye_height_and_faces_the_anchor_centre(tiny_dataset):
    for entry in _entries(tiny_dataset):
        cam = _camera(entry)
        assert cam.position[1] == 1.55
        centre = np.array(entry.object_landmark.raw_metadata.axisAlignedBoundingBox.center.as_tuple())
        u, v = cam.project(centre).normalized
        assert abs(u - 0.5) < 1e-3 and abs(v - 0.5) < 1e-3


def test_observer_and_anchor_show_together_in_some_exploration_frame(tiny_dataset):
    hits = [set(record["object_in_frame_hits"]) for record in tiny_dataset.log()]
    for entry in _entries(tiny_dataset):
        pair = {entry.object_observer.objectId, entry.object_landmark.objectId}
        assert any(pair <= frame for frame in hits), entry.pair_id
