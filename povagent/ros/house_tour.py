"""A generated house as a robot's recorded tour: frames, calibration, and poses in a z-up ``map``.

A generated house is AI2-THOR's world (y up, left-handed) with 512x512 exploration frames; a
ROS robot records a right-handed, z-up ``map`` (REP 103: x forward, y left, z up), a
``base_link`` on the floor under the camera turned to its heading, and a camera optical frame
(``camera_color_optical_frame``: z forward, x right, y down) mounted on the base. This module
turns a house's instance into that tour, so the examples and tests can publish or record it:

* map = ``THOR_TO_MAP @ thor`` (AI2-THOR's x right, y up, z forward become the map's -y, z, x);
* ``T_map_optical``: the exploration camera in OpenCV axes, in the map;
* ``T_map_base``: the camera's position dropped to z = 0, turned to the optical axis' heading;
* the mount ``T_base_optical`` is the same for every frame (exploration cameras share height and
  tilt): it is checked, not assumed.

Also here: what a perception simulation needs to answer for the house in the map
(:class:`TourTruth`: the anchor's and the observer furniture's boxes, the direction, the surface,
the ground-truth target). Reads the dataset's files; imports neither rclpy nor rosbags.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from povagent.geometry.goals import PinholeCamera
from povagent.ros.camera_info import Intrinsics
from povagent.ros.transforms import RigidTransform

#: AI2-THOR's axes (x right, y up, z forward) in the robot's map (x forward, y left, z up).
THOR_TO_MAP = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
MAP_FRAME = "map"
BASE_FRAME = "base_link"
CAMERA_FRAME = "camera_color_optical_frame"
#: Seconds between two frames of the tour (and its first stamp).
FRAME_PERIOD_S = 0.5
START_S = 100.0


@dataclass(frozen=True)
class TourFrame:
    """One recorded frame: stamp (ns), RGB pixels, the base's and the camera's poses in the map."""

    stamp_ns: int
    rgb: np.ndarray
    map_from_base: RigidTransform
    map_from_camera: np.ndarray


@dataclass(frozen=True)
class TourTruth:
    """What the house's records say about one command, in the map (for a simulation and for checking)."""

    sentence: str
    target: tuple[float, float, float]
    objects: dict[str, tuple[np.ndarray, np.ndarray]]
    anchor: str
    observer: str
    direction: str
    surface: str


@dataclass(frozen=True)
class HouseTour:
    """A house's exploration as a ROS robot would have recorded it."""

    frames: list[TourFrame]
    intrinsics: Intrinsics
    mount: RigidTransform
    truth: TourTruth

    def cameras(self) -> list[PinholeCamera]:
        """Each frame's camera (optical axes, in the map)."""
        return [self.intrinsics.camera(f.map_from_camera) for f in self.frames]


def base_pose(map_from_camera: np.ndarray) -> RigidTransform:
    """The base under a camera: its position at z = 0, yawed to the optical axis' heading."""
    forward = map_from_camera[:3, 2]
    yaw = math.atan2(forward[1], forward[0])
    x, y = float(map_from_camera[0, 3]), float(map_from_camera[1, 3])
    return RigidTransform((x, y, 0.0), (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)))


def house_tour(instance: Any, house: Any, period_s: float = FRAME_PERIOD_S) -> HouseTour:
    """The tour of ``instance``'s exploration frames (a loaded dataset's instance and house)."""
    from povagent.geometry.placement import surface_kind

    frames: list[TourFrame] = []
    mount: RigidTransform | None = None
    first = instance.frames[0].camera
    fx, fy, cx, cy = first.intrinsics
    intrinsics = Intrinsics(fx, fy, cx, cy, int(first.width), int(first.height))
    for i, frame in enumerate(instance.frames):
        thor = frame.camera
        if (thor.width, thor.height, tuple(thor.intrinsics)) != (intrinsics.width, intrinsics.height, (fx, fy, cx, cy)):
            raise ValueError(f"frame {i} has another calibration than frame 0: a tour has one camera")
        in_thor = PinholeCamera.from_camera(thor, "opencv").camera_to_world
        map_from_camera = np.eye(4)
        map_from_camera[:3, :3] = THOR_TO_MAP @ in_thor[:3, :3]
        map_from_camera[:3, 3] = THOR_TO_MAP @ in_thor[:3, 3]
        base = base_pose(map_from_camera)
        this_mount = np.linalg.inv(base.matrix()) @ map_from_camera
        if mount is None:
            mount = RigidTransform.from_matrix(this_mount)
        elif not np.allclose(mount.matrix(), this_mount, atol=1e-9):
            raise ValueError(f"frame {i}: the camera sits elsewhere on the base than in frame 0 (height or tilt differ)")
        with Image.open(Path(frame.file)) as im:
            rgb = np.asarray(im.convert("RGB"))
        stamp = int(round((START_S + i * period_s) * 1e9))
        frames.append(TourFrame(stamp, rgb, base, map_from_camera))
    assert mount is not None
    pair = house.pairs[instance.pair_id]
    objects = {}
    for obj in (instance.anchor_object, instance.observer_object):
        corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float) @ THOR_TO_MAP.T
        objects[obj.object_type] = (corners.min(axis=0), corners.max(axis=0))
    target = THOR_TO_MAP @ np.asarray(instance.target, dtype=float)
    truth = TourTruth(
        sentence=instance.sentence,
        target=(float(target[0]), float(target[1]), float(target[2])),
        objects=objects,
        anchor=instance.anchor_object.object_type,
        observer=instance.observer_object.object_type,
        direction=str(instance.direction),
        surface=surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type),
    )
    return HouseTour(frames, intrinsics, mount, truth)


def well_seen_instance(dataset: Any) -> tuple[Any, Any] | None:
    """The first Inferred instance whose anchor and observer furniture (of different types) each
    show in two or more exploration frames, with its house; ``None`` when there is none."""
    for instance in dataset.instances(conditions=["a"]):
        house = dataset.houses[instance.house_id]
        objects = (instance.anchor_object, instance.observer_object)
        seen = [sum(o.objectId in r.object_in_frame_hits for r in house.exploration) for o in objects]
        if min(seen) >= 2 and objects[0].object_type != objects[1].object_type:
            return instance, house
    return None


__all__ = ["BASE_FRAME", "CAMERA_FRAME", "MAP_FRAME", "THOR_TO_MAP", "HouseTour", "TourFrame", "TourTruth", "base_pose", "house_tour", "well_seen_instance"]
