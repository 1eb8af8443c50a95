"""A robot's cameras in the solver: conventions, letterboxed intrinsics, and its world mapped in.

The solver reasons in the benchmark's world (y up, floor at y = 0, left-handed) on the square
images the model sees. A robot's camera (any pose convention, any intrinsics, any frame size)
is brought there exactly: the letterbox's per-axis scale and offset go into the intrinsics, and
the robot's world is mapped by a rigid motion that keeps an observer's left and right.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from povagent.geometry.camera import Camera
from povagent.geometry.goals import FLOOR, PinholeCamera, Plane, camera_problem
from povagent.geometry.ground_truth import direction_vectors
from povagent.geometry.letterbox import Letterbox
from povagent.geometry.placement import choose_frame
from povagent.geometry.solver_world import SolverWorld
from povagent.geometry.triangulation import Outline, fit_box, projected_box

K_640 = [[520.0, 0.0, 331.5], [0.0, 515.0, 229.25], [0.0, 0.0, 1.0]]


def ros_pose(position, heading_deg: float, tilt_deg: float = 20.0) -> np.ndarray:
    """A camera_link pose (x forward, y left, z up) in a z-up map, turned and tilted down."""
    h, t = math.radians(heading_deg), math.radians(tilt_deg)
    yaw = np.array([[math.cos(h), -math.sin(h), 0.0], [math.sin(h), math.cos(h), 0.0], [0.0, 0.0, 1.0]])
    pitch = np.array([[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0], [-math.sin(t), 0.0, math.cos(t)]])  # nose down
    pose = np.eye(4)
    pose[:3, :3] = yaw @ pitch
    pose[:3, 3] = position
    return pose


# -- conventions ------------------------------------------------------------------------------------
def test_a_ros_camera_link_looks_along_its_x_axis_with_z_up():
    cam = PinholeCamera(np.eye(4), 500.0, 500.0, 320.0, 240.0, 640, 480, "ros")
    assert np.allclose(cam.ray(np.array([320.0, 240.0])), (1.0, 0.0, 0.0))
    assert cam.ray(np.array([320.0, 100.0]))[2] > 0  # higher in the image is up
    assert cam.ray(np.array([600.0, 240.0]))[1] < 0  # image right is the robot's right (-y)


def test_project_point_is_project_pixels_over_the_size_with_the_depth():
    cam = PinholeCamera.from_intrinsics(ros_pose((1.0, 2.0, 1.2), 35.0), K_640, 640, 480, "ros")
    point = np.array([3.0, 3.5, 0.4])
    u, v, depth = cam.project_point(point)
    assert np.allclose((u * 640, v * 480), cam.project_pixels(point))
    assert depth == pytest.approx(float((point - cam.position) @ cam.optical_axes()[2]))
    behind = cam.position - 2.0 * cam.optical_axes()[2]
    assert math.isnan(cam.project_point(behind)[0])


def test_a_pose_says_the_handedness_of_its_world():
    assert PinholeCamera.from_fov(ros_pose((0, 0, 1), 10.0), 60.0, 640, 480, "ros").right_handed
    assert not PinholeCamera.from_camera(Camera.from_pose((0, 0.9, 0), 30.0, 20.0)).right_handed  # Unity


def test_the_field_of_view_is_the_widths_as_ai2thors():
    thor = Camera.from_pose((0, 0.9, 0), 0.0, 0.0, fov=100.0)
    assert PinholeCamera.from_camera(thor).fov == pytest.approx(100.0)


# -- letterbox ------------------------------------------------------------------------------------
@pytest.mark.parametrize("size", [(640, 480), (1280, 720), (480, 640), (512, 512)])
def test_the_letterboxed_camera_sees_each_point_where_the_letterbox_puts_its_pixel(size):
    w, h = size
    k = [[0.8 * w, 0.0, 0.52 * w], [0.0, 0.79 * w, 0.47 * h], [0.0, 0.0, 1.0]]
    cam = PinholeCamera.from_intrinsics(ros_pose((0.0, 0.0, 1.0), 0.0), k, w, h, "ros")
    box = Letterbox.for_size(w, h)
    square = cam.letterboxed(box)
    points = np.array([[3.0, 0.4, 0.2], [2.0, -0.5, 1.4], [5.0, 1.0, 0.0]])
    assert np.allclose(square.project_pixels(points), box.to_square(cam.project_pixels(points)), atol=1e-9)
    pixels = np.array([[10.0, 20.0], [w / 2, h / 2], [w - 3.0, h - 1.0]])
    assert np.allclose(square.ray(box.to_square(pixels)), cam.ray(pixels), atol=1e-12)
    assert square.content_box == tuple(float(v) for v in box.content_box())
    assert (square.width, square.height) == (512, 512)


def test_box_edges_on_the_letterbox_border_are_left_out_as_the_images_own_border_is():
    thor = Camera.from_pose((-1.5, 0.9, 0.5), 60.0, 30.0)
    cam = PinholeCamera.from_camera(thor).letterboxed(Letterbox.for_size(512, 512))  # a plain square
    wide = PinholeCamera.from_intrinsics(np.eye(4), K_640, 640, 480).letterboxed(Letterbox.for_size(640, 480))
    top, bottom = wide.content_box[1], wide.content_box[3]
    assert (top, bottom) == (64.0, 448.0)
    centre, half = np.array([0.0, 0.0, 4.0]), np.array([0.3, 0.3, 0.3])
    x0, _, x1, _ = projected_box(wide, centre, half)
    cut = fit_box(centre, [Outline(wide, (x0, top, x1, bottom - 1.0))], prior_half=(0.3, 0.3, 0.3))
    assert cut.edges_used == 2  # the top and bottom edges lie on the padding's border: they bound nothing
    assert cam.content_box == (0.0, 0.0, 512.0, 512.0)


def test_a_target_on_the_padding_is_not_in_frame():
    wide = PinholeCamera.from_intrinsics(np.eye(4), K_640, 640, 480).letterboxed(Letterbox.for_size(640, 480))
    above_the_view = np.array([0.0, -2.0, 4.0])  # OpenCV y is down: 2 m up, 4 m ahead
    _u, v, _ = wide.project_point(above_the_view)
    assert 0.0 < v * 512 < 64.0  # inside the square, on its padding
    choice = choose_frame(above_the_view, [wide])
    assert choice.placement == "in front, outside the frame" and choice.pixel[1] == 64.0


# -- the robot's world ----------------------------------------------------------------------------
def test_ai2thors_world_is_the_solvers_own():
    world = SolverWorld.for_floor(FLOOR, right_handed=False)
    assert np.array_equal(np.abs(world.rotation), np.eye(3)) and np.allclose(world.rotation, np.eye(3))
    assert np.array_equal(world.origin, np.zeros(3))


@pytest.mark.parametrize(
    ("floor", "right_handed", "forward", "right"),
    [
        (Plane.horizontal(0.3, up_axis="z"), True, (1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),  # ROS map: y is left
        (Plane.horizontal(-0.2, up_axis="y"), True, (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),  # OpenGL: looks along -z
        (Plane.horizontal(0.0, up_axis="y"), False, (0.0, 0.0, 1.0), (1.0, 0.0, 0.0)),  # Unity
    ],
    ids=["ros-map", "opengl-world", "unity"],
)
def test_an_observers_right_in_the_robots_world_is_the_benchmarks_right(floor, right_handed, forward, right):
    world = SolverWorld.for_floor(floor, right_handed)
    up = np.asarray(floor.normal)
    observer = np.asarray(floor.point) + 1.5 * up
    anchor = observer + 2.0 * np.asarray(forward) - 1.0 * up
    directions = direction_vectors(world.to_solver(anchor), world.to_solver(observer))
    assert np.allclose(directions["right"] @ world.rotation, right)  # back in the robot's world
    assert world.to_solver(np.asarray(floor.point))[1] == pytest.approx(0.0)  # the floor is y = 0
    assert world.to_solver(observer)[1] == pytest.approx(1.5)  # heights are the up axis'


def test_the_maps_axes_stay_the_solvers_horizontal_axes():
    world = SolverWorld.for_floor(Plane.horizontal(0.0, up_axis="z"), right_handed=True)
    # a signed permutation: furniture aligned with the map stays aligned with the solver's boxes
    assert np.array_equal(np.abs(world.rotation), [[1, 0, 0], [0, 0, 1], [0, 1, 0]])
    points = np.array([[1.0, 2.0, 3.0], [-4.0, 0.5, 0.0]])
    assert np.allclose(world.to_world(world.to_solver(points)), points)


def test_a_camera_moved_into_the_solvers_world_sees_the_same_pixels():
    world = SolverWorld.for_floor(Plane.horizontal(0.3, up_axis="z"), right_handed=True)
    cam = PinholeCamera.from_intrinsics(ros_pose((2.0, -1.0, 1.3), 120.0), K_640, 640, 480, "ros")
    moved = cam.moved(world.rotation, world.origin)
    points = np.array([[1.0, 0.5, 0.8], [0.0, 1.0, 0.3]])
    assert np.allclose(moved.project_pixels(world.to_solver(points)), cam.project_pixels(points))
    assert not moved.right_handed  # the solver's world is AI2-THOR's: left-handed


# -- bad cameras ------------------------------------------------------------------------------------
def test_a_sound_camera_has_no_problem():
    assert camera_problem(PinholeCamera.from_intrinsics(ros_pose((0, 0, 1), 0.0), K_640, 640, 480, "ros")) is None
    assert camera_problem(Camera.from_pose((0, 0.9, 0), 0.0, 30.0)) is None


def test_a_bad_camera_is_named_by_its_problem():
    cam = PinholeCamera.from_intrinsics(ros_pose((0, 0, 1), 0.0), K_640, 640, 480, "ros")
    cam.camera_to_world[0, 3] = math.inf
    assert "NaN or infinite" in camera_problem(cam)
    sheared = PinholeCamera.from_intrinsics(ros_pose((0, 0, 1), 0.0), K_640, 640, 480, "ros")
    sheared.camera_to_world[0, 1] += 0.3
    assert "not a rigid motion" in camera_problem(sheared)
    assert "fov must be in (0, 180)" in camera_problem(Camera.from_pose((0, 0.9, 0), 0.0, 30.0, fov=180.0))
    assert "NaN" in camera_problem(Camera.from_pose((0, 0.9, 0), math.nan, 30.0))


def test_building_a_pinhole_camera_from_a_non_rigid_pose_fails_at_once():
    with pytest.raises(ValueError, match="not orthonormal"):
        PinholeCamera.from_intrinsics(np.diag([2.0, 2.0, 2.0, 1.0]), K_640, 640, 480)
