"""The ``probe-anchor`` and ``probe-observer`` scorers, by hand.

One camera at the origin, horizon 0, 90 degree field of view on a 512 px frame (f = 256 px),
looking along +z: a point (x, y, z) lands at u = 256 + 256 x/z, v = 256 - 256 y/z. The anchor's
box is centred at (0, 0, 4), 2 x 1 x 2 m: its nearest face (z = 3) spans x in [-1, 1] and
y in [-0.5, 0.5], so its outline is [256 - 256/3, 256 - 128/3, 256 + 256/3, 256 + 128/3] px and
its centre (256, 256) px. The observer's 0.5 m box is centred at (3, 0, 2): its centre lands at
u = 256 + 384 = 640, beyond the right edge (the official rules clamp it to u = 1).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import AxisAlignedBoundingBox, Condition, Direction, RawMetadata, SceneObject, Vec3
from povagent.geometry.camera import Camera
from povagent_plugins.scorers.probe import AnchorProbeScorer, ObserverProbeScorer

CAMERA = Camera.from_pose((0.0, 0.0, 0.0), 0.0, 0.0, 90.0, 512, 512)
LEFT, TOP, RIGHT, BOTTOM = 256 - 256 / 3, 256 - 128 / 3, 256 + 256 / 3, 256 + 128 / 3


def box_object(object_type: str, center, size) -> SceneObject:
    cx, cy, cz = center
    hx, hy, hz = (s / 2 for s in size)
    corners = [[cx + sx * hx, cy + sy * hy, cz + sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    box = AxisAlignedBoundingBox(center=Vec3(x=cx, y=cy, z=cz), size=Vec3(x=size[0], y=size[1], z=size[2]), cornerPoints=corners)
    return SceneObject(
        objectId=f"{object_type}|1", position=Vec3(x=cx, y=cy, z=cz), raw_metadata=RawMetadata(objectType=object_type, axisAlignedBoundingBox=box)
    )


def instance(condition: Condition = Condition.INFERRED, hits=("Desk|1",)) -> Instance:
    frames = (Frame(0, "exploration_images/frame_000.png", Path("frame_000.png"), CAMERA, frozenset(hits)),)
    return Instance(house_id="h", pair_id="0", direction=Direction.LEFT, condition=condition, sentence="", frames=frames,
                    target=(0.0, 0.0, 3.0), observer_object=box_object("Sofa", (3.0, 0.0, 2.0), (0.5, 0.5, 0.5)),
                    anchor_object=box_object("Desk", (0.0, 0.0, 4.0), (2.0, 1.0, 2.0)), observer_camera=CAMERA)  # fmt: skip


def point(x: float, y: float, frame: int | None = 0) -> ParsedAnswer:
    return ParsedAnswer(status=ParseStatus.OK, selected_image=frame, x=x, y=y)


def test_a_point_inside_the_anchors_box_has_no_box_error():
    scores = AnchorProbeScorer().score(instance(), point(300.0, 280.0))
    assert scores["inside_box"] is True and scores["box_error"] == 0.0 and scores["in_view"] is True
    assert scores["centre_error"] == pytest.approx(math.hypot(44, 24) / 512)
    assert scores["object_type"] == "Desk" and scores["seen"] is True


def test_a_point_beside_the_box_is_its_distance_to_the_nearest_edge():
    scores = AnchorProbeScorer().score(instance(), point(400.0, 256.0))
    assert scores["inside_box"] is False
    assert scores["box_error"] == pytest.approx((400 - RIGHT) / 512)
    assert scores["centre_error"] == pytest.approx(144 / 512)


def test_a_point_off_a_corner_measures_along_both_axes():
    scores = AnchorProbeScorer().score(instance(), point(100.0, 450.0))
    assert scores["box_error"] == pytest.approx(math.hypot(LEFT - 100, 450 - BOTTOM) / 512)


def test_a_point_outside_the_image_is_clamped_as_officially():
    scores = AnchorProbeScorer().score(instance(), point(-300.0, 256.0))
    assert scores["box_error"] == pytest.approx(LEFT / 512)  # clamped to x = 0 first
    assert scores["centre_error"] == pytest.approx(0.5)


def test_an_object_outside_the_image_has_no_box_and_its_centre_clamped():
    scores = ObserverProbeScorer().score(instance(), point(511.0, 256.0))
    assert scores["in_view"] is False and scores["box_error"] is None and scores["inside_box"] is None
    assert scores["centre_error"] == pytest.approx(1.0 - 511 / 512)  # the centre clamped to u = 1
    assert scores["seen"] is False  # the frame's record lists the anchor only


def test_in_given_the_anchor_counts_as_seen_and_the_observer_never():
    given = instance(Condition.GIVEN, hits=())
    assert AnchorProbeScorer().score(given, point(256.0, 256.0, None))["seen"] is True
    assert ObserverProbeScorer().score(given, point(256.0, 256.0, None))["seen"] is False


def test_an_unanswered_row_or_an_unknown_frame_is_not_scored():
    assert AnchorProbeScorer().score(instance(), ParsedAnswer(status=ParseStatus.UNPARSEABLE)) == {"answered": False}
    assert AnchorProbeScorer().score(instance(), point(10.0, 10.0, 5)) == {"answered": False}
