"""Hand-built instances with known cameras, for strategy and marker tests.

Frames are plain grey PNGs written to a temporary folder; cameras sit at the origin at a height
of 0 looking along +z (yaw 0, horizon 0) with a 90 degree field of view, so the focal length is
W/2 = 256 px and a point (x, y, z) projects to u = 256 + 256 x/z, v = 256 - 256 y/z. Every frame
lists both objects (``Sofa|1`` the observer, ``Desk|1`` the anchor) in its ``in_frame_hits``
unless the test says otherwise.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from povagent.dataset.instances import Frame, Instance
from povagent.dataset.release_models import AxisAlignedBoundingBox, Condition, Direction, RawMetadata, SceneObject, Vec3
from povagent.geometry.camera import Camera

GREY = (128, 128, 128)


OBSERVER_ID, ANCHOR_ID = "Sofa|1", "Desk|1"


def scene_object(object_type: str, position, center, size, raw_position=None) -> SceneObject:
    """A scene object whose AABB is given by centre and size (corner points computed);
    ``raw_position`` is its ``raw_metadata.position`` (none by default: the box centre stands in)."""
    cx, cy, cz = center
    hx, hy, hz = (s / 2 for s in size)
    corners = [[cx + sx * hx, cy + sy * hy, cz + sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    box = AxisAlignedBoundingBox(center=Vec3(x=cx, y=cy, z=cz), size=Vec3(x=size[0], y=size[1], z=size[2]), cornerPoints=corners)
    raw_pos = None if raw_position is None else Vec3(x=raw_position[0], y=raw_position[1], z=raw_position[2])
    return SceneObject(
        objectId=f"{object_type}|1",
        position=Vec3(x=position[0], y=position[1], z=position[2]),
        raw_metadata=RawMetadata(objectType=object_type, axisAlignedBoundingBox=box, position=raw_pos),
    )


def grey_frame(path: Path, size=(512, 512)) -> Path:
    Image.new("RGB", size, GREY).save(path)
    return path


@pytest.fixture
def make_instance(tmp_path):
    """``make_instance(cameras, condition=a, observer=(1, 0, 2), anchor=((0, 0, 4), (2, 1, 2)),
    hits=(observer, anchor ids))``; ``observer`` may be a SceneObject, ``hits`` the same for every frame."""

    def make(cameras, condition=Condition.INFERRED, observer=(1.0, 0.0, 2.0), anchor=((0.0, 0.0, 4.0), (2.0, 1.0, 2.0)),
             sentence="I saw it left of the desk.", hits=(OBSERVER_ID, ANCHOR_ID)):
        frames = tuple(
            Frame(i, f"exploration_images/frame_{i:03d}.png", grey_frame(tmp_path / f"frame_{i:03d}_{id(cameras)}.png", (cam.width, cam.height)),
                  cam, frozenset(hits))
            for i, cam in enumerate(cameras)
        )
        if not isinstance(observer, SceneObject):
            observer = scene_object("Sofa", observer, observer, (0.5, 0.5, 0.5))
        if not isinstance(anchor, SceneObject):
            anchor = scene_object("Desk", anchor[0], anchor[0], anchor[1])
        return Instance(
            house_id="house_t",
            pair_id="0",
            direction=Direction.LEFT,
            condition=condition,
            sentence=sentence,
            frames=frames,
            target=(0.0, 0.0, 3.0),
            observer_object=observer,
            anchor_object=anchor,
            observer_camera=cameras[0],
        )

    return make


def _facing_z(yaw: float = 0.0, width: int = 512, height: int = 512) -> Camera:
    return Camera.from_pose((0.0, 0.0, 0.0), yaw, 0.0, 90.0, width, height)


@pytest.fixture
def facing_z():
    """``facing_z(yaw=0)``: a camera at the origin, horizon 0, fov 90 (f = W/2)."""
    return _facing_z


@pytest.fixture
def make_object():
    """``make_object(object_type, position, center, size, raw_position=None)``: :func:`scene_object`."""
    return scene_object


@pytest.fixture
def object_ids():
    """``(observer id, anchor id)`` of :func:`make_instance`'s objects."""
    return OBSERVER_ID, ANCHOR_ID
