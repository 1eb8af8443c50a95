"""GroundingAgent(strategy="geometric") takes the robot's cameras in any form and returns the
goal in the robot's own world.

One generated scene, its cameras given four ways: (a) AI2-THOR's ``Camera`` (y up, left-handed),
(b) 4x4 OpenCV optical poses in a ROS-style map (z up, right-handed, turned 90 degrees, moved,
the floor at z = 0.3), (c) the same map with ROS ``camera_link`` poses (x forward, y left,
z up), (d) the frames resized to 640x640 and cropped off-centre to 640x480, with the matching
intrinsics (the principal point is then off the image centre) and the poses of (b). Perception
is exact (the scene simulator with sigma 0), so every goal must be the same point, written in
each world: (a)-(c) see the very same square images, (d) sees other pixels of the same scene.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from PIL import Image

from povagent.agent import GroundingAgent
from povagent.dataset.loader import load_dataset
from povagent.errors import BadInputError
from povagent.geometry.camera import Camera
from povagent.geometry.goals import PinholeCamera, Plane
from povagent.geometry.placement import surface_kind
from povagent_plugins.backends.simulated import SimulatedScene

#: AI2-THOR (x right, y up, z forward; left-handed) to a ROS map (x forward, y left, z up),
#: then turned 90 degrees about z: a reflection, as a change of handedness must be.
TURN = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
THOR_TO_MAP = TURN @ np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
MAP_OFFSET = np.array([5.0, -2.0, 0.3])
MAP_FLOOR = Plane.horizontal(0.3, up_axis="z")

#: (a)-(c) see identical images: their goals agree to numerical precision (m).
SAME_IMAGES_TOLERANCE = 1e-4
#: Exact perception: the goal is the benchmark's ground truth within the box fit's error (m).
GROUND_TRUTH_TOLERANCE = 0.05
#: (d) crops part of the view away: fewer and other box edges, the fit moves a little (m).
CROPPED_TOLERANCE = 0.05

CROP = (640, 480, 40)  # width, height, rows cut off the top of the 640x640 resize


def to_map(point) -> np.ndarray:
    """An AI2-THOR world point in the robot's map."""
    return THOR_TO_MAP @ np.asarray(point, dtype=float) + MAP_OFFSET


def map_pose(camera: Camera, convention: str) -> np.ndarray:
    """The camera's 4x4 camera-to-map pose, its axes in ``convention``."""
    thor = PinholeCamera.from_camera(camera, convention).camera_to_world
    pose = np.eye(4)
    pose[:3, :3] = THOR_TO_MAP @ thor[:3, :3]
    pose[:3, 3] = to_map(thor[:3, 3])
    return pose


def box_of(obj):
    corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float)
    return corners.min(axis=0), corners.max(axis=0)


def map_box(lo, hi):
    corners = np.array([to_map((x, y, z)) for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    return corners.min(axis=0), corners.max(axis=0)


@pytest.fixture(scope="module")
def scene(generated_release):
    """An Inferred instance whose anchor and observer (of different types) are each seen in at
    least three frames, with its records."""
    dataset = load_dataset(generated_release)
    for instance in dataset.instances(conditions=["a"]):
        house = dataset.houses[instance.house_id]
        objects = (instance.anchor_object, instance.observer_object)
        seen = [sum(o.objectId in r.object_in_frame_hits for r in house.exploration) for o in objects]
        if min(seen) >= 3 and objects[0].object_type != objects[1].object_type and str(instance.direction) != "up":
            return instance, house.pairs[instance.pair_id]
    raise AssertionError("no well-seen instance in the generated set")


def goal_of(scene, frames, cameras, objects, plane=None):
    """The agent's goal with exact perception of ``objects`` through ``cameras``."""
    instance, pair = scene
    backend = SimulatedScene(
        objects,
        cameras,
        observer=instance.observer_object.object_type,
        anchor=instance.anchor_object.object_type,
        direction=str(instance.direction),
        surface=surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type),
    )
    options = {"plane": plane} if plane is not None else {}
    with GroundingAgent(backend=backend, strategy="geometric", parser="json", **options) as agent:
        found = agent.locate(instance.sentence, frames, cameras=cameras)
    assert found.goal is not None and found.goal.method == "geometry", found.raw_answer
    return np.array(found.goal.point)


def thor_objects(instance):
    return {o.object_type: box_of(o) for o in (instance.anchor_object, instance.observer_object)}


def map_objects(instance):
    return {o.object_type: map_box(*box_of(o)) for o in (instance.anchor_object, instance.observer_object)}


@pytest.fixture(scope="module")
def thor_goal(scene):
    instance, _ = scene
    return goal_of(scene, [f.file for f in instance.frames], [f.camera for f in instance.frames], thor_objects(instance))


def test_ai2thor_cameras_give_the_ground_truth(scene, thor_goal):
    instance, _ = scene
    assert np.linalg.norm(thor_goal - np.array(instance.target)) < GROUND_TRUTH_TOLERANCE


@pytest.mark.parametrize("convention", ["opencv", "ros", "opengl"])
def test_poses_in_a_z_up_map_give_the_same_goal_in_the_map(scene, thor_goal, convention):
    instance, _ = scene
    cameras = [PinholeCamera(map_pose(f.camera, convention), *f.camera.intrinsics, 512, 512, convention) for f in instance.frames]
    goal = goal_of(scene, [f.file for f in instance.frames], cameras, map_objects(instance), MAP_FLOOR)
    assert np.linalg.norm(goal - to_map(thor_goal)) < SAME_IMAGES_TOLERANCE


def cropped(frame_file, width: int, height: int, top: int) -> Image.Image:
    with Image.open(frame_file) as im:
        return im.convert("RGB").resize((width, width), Image.Resampling.BICUBIC).crop((0, top, width, top + height))


def test_640x480_crops_with_matching_intrinsics_give_the_same_goal(scene, thor_goal):
    instance, _ = scene
    width, height, top = CROP
    scale = width / instance.frames[0].camera.width
    frames, cameras = [], []
    for f in instance.frames:
        fx, fy, cx, cy = f.camera.intrinsics
        k = [[fx * scale, 0.0, cx * scale], [0.0, fy * scale, cy * scale - top], [0.0, 0.0, 1.0]]
        cameras.append(PinholeCamera.from_intrinsics(map_pose(f.camera, "opencv"), k, width, height, "opencv"))
        frames.append(cropped(f.file, width, height, top))
    assert cameras[0].cy != height / 2  # the principal point is off the image centre
    goal = goal_of(scene, frames, cameras, map_objects(instance), MAP_FLOOR)
    assert np.linalg.norm(goal - to_map(thor_goal)) < CROPPED_TOLERANCE
    assert np.linalg.norm(goal - to_map(instance.target)) < GROUND_TRUTH_TOLERANCE


# -- bad cameras ----------------------------------------------------------------------------------
def agent_call(scene, cameras, frames=None):
    instance, _ = scene
    frames = frames if frames is not None else [f.file for f in instance.frames[: len(cameras)]]
    backend = SimulatedScene(thor_objects(instance), [c for c in cameras if c is not None], anchor="Sofa", direction="left", surface="floor")
    with GroundingAgent(backend=backend, strategy="geometric", parser="json") as agent:
        return agent.locate(instance.sentence, frames, cameras=cameras)


def test_a_camera_with_nan_is_refused_naming_it(scene):
    instance, _ = scene
    good = instance.frames[0].camera
    bad = Camera((math.nan, 0.9, 1.0), 0.0, 30.0)
    with pytest.raises(BadInputError, match=r"cameras\[1\]: the camera holds NaN"):
        agent_call(scene, [good, bad])


def test_a_pose_that_is_not_a_rigid_motion_is_refused_naming_it(scene):
    instance, _ = scene
    cameras = [PinholeCamera(map_pose(f.camera, "opencv"), *f.camera.intrinsics, 512, 512) for f in instance.frames[:2]]
    cameras[1].camera_to_world[:3, :3] *= 2.0  # the robot's pose buffer scaled after the camera was built
    with pytest.raises(BadInputError, match=r"cameras\[1\]: the camera-to-world pose is not a rigid motion"):
        agent_call(scene, cameras)


def test_a_camera_of_another_size_than_its_frame_is_refused_naming_it(scene):
    instance, _ = scene
    cameras = [f.camera for f in instance.frames[:2]]
    frames = [instance.frames[0].file, cropped(instance.frames[1].file, *CROP)]
    with pytest.raises(BadInputError, match=r"cameras\[1\] describes a 512x512 image but the frame is 640x480"):
        agent_call(scene, cameras, frames)


def test_cameras_of_two_worlds_are_refused(scene):
    instance, _ = scene
    thor = instance.frames[0].camera
    in_map = PinholeCamera(map_pose(instance.frames[1].camera, "opencv"), *thor.intrinsics, 512, 512)
    with pytest.raises(BadInputError, match=r"cameras\[1\] is posed in a right-handed world but cameras\[0\] in a left-handed one"):
        agent_call(scene, [thor, in_map])


def test_the_geometric_strategy_needs_every_frames_camera(scene):
    instance, _ = scene
    with pytest.raises(BadInputError, match=r"cameras\[1\]: the geometric strategy triangulates with every frame's camera"):
        agent_call(scene, [instance.frames[0].camera, None])


# -- the observer view (C) ------------------------------------------------------------------------
def given_scene(generated_release):
    dataset = load_dataset(generated_release)
    instance = next(i for i in dataset.instances(conditions=["c"]) if str(i.direction) != "up")
    pair = dataset.houses[instance.house_id].pairs[instance.pair_id]
    return instance, pair


def test_an_observer_view_needs_no_camera_and_its_pixel_is_the_answer(generated_release):
    instance, pair = given_scene(generated_release)
    view = instance.frames[0]
    backend = SimulatedScene(
        {instance.anchor_object.object_type: box_of(instance.anchor_object)}, [view.camera],
        anchor=instance.anchor_object.object_type, direction=str(instance.direction),
        surface=surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type),
    )
    with GroundingAgent(backend=backend, strategy="geometric", parser="json") as agent:
        found = agent.locate(instance.sentence, observer_view=view.file)
    assert found.goal is None and "fallbacks: none" in found.raw_answer
    u, v, _ = view.camera.project_point(instance.target)
    assert np.hypot(found.pixel[0] - u * 512, found.pixel[1] - v * 512) < 0.1 * 512  # near the truth in the image


def test_an_observer_views_robot_camera_lends_its_field_of_view_and_makes_a_floor_goal(generated_release):
    instance, _ = given_scene(generated_release)
    view = instance.frames[0]
    camera = PinholeCamera(map_pose(view.camera, "opencv"), *view.camera.intrinsics, 512, 512)
    backend = SimulatedScene(
        {instance.anchor_object.object_type: map_box(*box_of(instance.anchor_object))}, [camera],
        anchor=instance.anchor_object.object_type, direction=str(instance.direction), surface="floor",
    )
    with GroundingAgent(backend=backend, strategy="geometric", parser="json", plane=MAP_FLOOR) as agent:
        found = agent.locate(instance.sentence, observer_view=view.file, cameras=camera)
    assert found.goal is not None and found.goal.method == "plane"  # no pose in C: the pixel is back-projected
    assert found.goal.point[2] == pytest.approx(MAP_FLOOR.point[2])
