"""The observer view shows the anchor and looks at its centre from 1.55 m."""

from __future__ import annotations

import numpy as np

from povagent.dataset.models import PairEntry
from povagent.generate.pairs import MIN_ANCHOR_PIXELS
from povagent.geometry.camera import Camera


def _instance_id(tiny_dataset, object_id: str) -> int:
    objects = tiny_dataset.built.house.objects
    return next(k + 1 for k, o in enumerate(objects) if o.object_id == object_id)


def test_the_observer_view_instance_mask_shows_the_anchor(tiny_dataset):
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        mask = tiny_dataset.instance(str(entry.pair_id))
        anchor = _instance_id(tiny_dataset, entry.object_landmark.objectId)
        assert int(np.sum(mask == anchor)) >= MIN_ANCHOR_PIXELS, entry.pair_id


def test_the_observer_camera_is_at_eye_height_and_faces_the_anchor_centre(tiny_dataset):
    for entry in map(PairEntry.model_validate, tiny_dataset.pairs()):
        cam = Camera.from_pose(entry.camera.cam_pos, entry.camera.cam_yaw, entry.camera.cam_horizon)
        assert cam.position[1] == 1.55
        centre = np.array(entry.object_landmark.raw_metadata.axisAlignedBoundingBox.center.as_tuple())
        u, v = cam.project(centre).normalized
        assert abs(u - 0.5) < 1e-3 and abs(v - 0.5) < 1e-3
