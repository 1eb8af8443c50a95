"""Furniture meshes are composites that fill the ProcTHOR box; door frames do not z-fight."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate.assets import OBSERVER_ANCHOR_CATEGORIES, asset_database
from povagent.generate.floorplan import DOOR_HEIGHT, Opening
from povagent.generate.furnishing import DOOR_FRAME_TRIM, doorway_object
from povagent.generate.meshes import object_parts
from povagent.generate.scene import PlacedObject


def _object(object_type: str, asset_index: int = 0) -> PlacedObject:
    spec = asset_database()[object_type][asset_index]
    return PlacedObject("x", object_type, spec.asset_id, (0.0, spec.size[1] / 2, 0.0), spec.size, 0, 0, style=3)


@pytest.mark.parametrize("object_type", OBSERVER_ANCHOR_CATEGORIES)
def test_every_category_is_built_from_parts_inside_its_procthor_box(object_type):
    obj = _object(object_type)
    parts = [p for p in object_parts(obj).items if not p[4]]  # decoration (towels) hangs outside
    assert len(parts) >= 2, "a bare box is not recognizable furniture"
    w, h, d = obj.local_size
    for vertices, *_ in parts:
        assert np.all(np.abs(vertices[:, 0]) <= w / 2 + 0.02) and np.all(np.abs(vertices[:, 2]) <= d / 2 + 0.02)
        assert np.all(vertices[:, 1] >= -1e-9) and np.all(vertices[:, 1] <= h + 0.02)


def test_a_bed_has_a_frame_mattress_pillows_and_a_headboard():
    assert len(object_parts(_object("Bed")).items) >= 6


def test_door_frames_reach_past_the_walls_cut_faces_instead_of_sharing_them():
    # flush faces of two boxes z-fight into a speckled frame: the jambs and the head must
    # overlap the opening, so the wall's cut faces (and baseboard ends) lie inside them
    obj = doorway_object(Opening((0, 1), "x", 0.0, 0.0, 1.0), 0)
    w = obj.local_size[0]
    half_opening = w / 2 - DOOR_FRAME_TRIM
    jambs, head = [], []
    for vertices, *_ in object_parts(obj).items:
        xs, ys = vertices[:, 0], vertices[:, 1]
        (head if ys.min() > 1.0 else jambs).append((xs.min(), xs.max(), ys.min()))
    inner = [min(abs(x0), abs(x1)) for x0, x1, _ in jambs]
    assert len(jambs) == 2 and max(inner) < half_opening - 0.01
    assert head and head[0][2] < DOOR_HEIGHT - 0.01
