"""3D goals: back-projection against the geometry module and the generator's depth maps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from povagent.dataset import load_dataset
from povagent.generate import generate_dataset
from povagent.generate.house_pipeline import build_house
from povagent.geometry.camera import Camera
from povagent.geometry.goals import (
    GoalUnavailable,
    PinholeCamera,
    Plane,
    PoseConvention,
    at_depth,
    back_project,
    depth_at,
    on_plane,
)
from povagent.geometry.letterbox import Letterbox

CAMERAS = [
    Camera.from_pose([1.0, 0.9, 2.0], 37.0, 30.0),
    Camera.from_pose([-2.5, 1.55, 0.3], 200.0, 12.0, fov=60.0, width=1280, height=720),
    Camera.from_pose([0.0, 1.2, 0.0], 300.0, -5.0, fov=90.0, width=480, height=640),
]
PIXELS = np.array([[0.0, 0.0], [10.25, 400.75], [240.0, 320.0], [479.0, 639.0], [111.1, 222.2]])


@pytest.mark.parametrize("convention", list(PoseConvention))
@pytest.mark.parametrize("camera", CAMERAS, ids=["square", "wide", "tall"])
def test_a_4x4_pose_describes_the_same_rays_as_our_camera(camera, convention):
    pinhole = PinholeCamera.from_camera(camera, convention)
    assert np.allclose(pinhole.ray(PIXELS), camera.ray(PIXELS), atol=1e-12)
    assert np.allclose(pinhole.point_at_depth(PIXELS, 3.5), camera.point_at_depth(PIXELS, 3.5), atol=1e-12)


@pytest.mark.parametrize("convention", list(PoseConvention))
def test_pinhole_projection_inverts_point_at_depth(convention):
    pinhole = PinholeCamera.from_camera(CAMERAS[1], convention)
    points = pinhole.point_at_depth(PIXELS, np.array([0.5, 1.0, 2.0, 4.0, 8.0]))
    assert np.allclose(pinhole.project_pixels(points), PIXELS, atol=1e-9)


def test_opengl_pose_looks_along_minus_z():
    pose = np.eye(4)  # camera at the origin, OpenGL: looks along world -z
    cam = PinholeCamera.from_fov(pose, 90.0, 100, 100, "opengl")
    assert np.allclose(cam.ray(np.array([50.0, 50.0])), [0.0, 0.0, -1.0])
    # image y down = camera y up negated: a pixel below the centre looks downward (-y)
    assert cam.ray(np.array([50.0, 90.0]))[1] < 0


def test_intrinsics_matrix_sets_focal_length_and_principal_point():
    k = [[500.0, 0, 300.0], [0, 400.0, 200.0], [0, 0, 1]]
    cam = PinholeCamera.from_intrinsics(np.eye(4), k, 640, 480)
    assert np.allclose(cam.project_pixels(np.array([0.0, 0.0, 2.0])), [300.0, 200.0])
    assert np.allclose(cam.project_pixels(np.array([1.0, 1.0, 2.0])), [550.0, 400.0])


def test_a_scaled_pose_is_rejected():
    with pytest.raises(ValueError, match="not orthonormal"):
        PinholeCamera.from_fov(np.diag([2.0, 2.0, 2.0, 1.0]), 60.0, 640, 480)


def test_floor_goal_matches_the_camera_module():
    cam = CAMERAS[0]
    for px in ([256.0, 400.0], [30.0, 500.0], [500.0, 300.0]):
        goal = on_plane(cam, px)
        assert goal.method == "plane"
        assert np.allclose(goal.point, cam.point_on_plane(np.array(px)), atol=1e-12)


def test_a_pixel_above_the_horizon_has_no_floor_goal():
    cam = Camera.from_pose([0.0, 1.0, 0.0], 0.0, 0.0)  # level camera: the top half sees no floor
    with pytest.raises(GoalUnavailable, match="behind the camera"):
        on_plane(cam, (256.0, 10.0))


def test_ros_robot_floor_in_a_z_up_world():
    # OpenCV camera 1 m above a z-up floor, looking along world +x, level
    pose = np.eye(4)
    pose[:3, :3] = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])  # columns: right, down, forward
    pose[:3, 3] = [0.0, 0.0, 1.0]
    cam = PinholeCamera.from_intrinsics(pose, [[100.0, 0, 320.0], [0, 100.0, 240.0], [0, 0, 1]], 640, 480)
    goal = on_plane(cam, (320.0, 290.0), Plane.horizontal(0.0, up_axis="z"))
    # 50 px below the centre at f = 100: the ray drops 1 m in 2 m
    assert np.allclose(goal.point, [2.0, 0.0, 0.0])


def test_z_and_range_depth_give_the_same_point():
    cam = CAMERAS[1]
    px = np.array([100.5, 600.5])
    z = 3.0
    rng = z * np.linalg.norm([(px[0] - 640) / cam.focal_px, (360 - px[1]) / cam.focal_px, 1.0])
    a = at_depth(cam, px, np.full((720, 1280), z), depth_kind="z")
    b = at_depth(cam, px, np.full((720, 1280), rng), depth_kind="range")
    assert np.allclose(a.point, b.point, atol=1e-9)
    assert a.method == "depth" and np.isclose(a.distance, rng)


def test_a_depth_image_of_another_resolution_is_sampled_at_the_same_fraction():
    depth = np.arange(12, dtype=float).reshape(3, 4)  # 4 wide, 3 high
    assert depth_at(depth, (1279.0, 719.0), (1280, 720)) == 11.0
    assert depth_at(depth, (0.0, 0.0), (1280, 720)) == 0.0
    assert depth_at(depth, (640.0, 360.0), (1280, 720)) == 6.0


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf])
def test_a_missing_depth_reading_is_not_a_goal(bad):
    with pytest.raises(GoalUnavailable, match="no valid depth"):
        at_depth(CAMERAS[0], (10.0, 10.0), np.full((4, 4), bad))


def test_back_project_prefers_depth_over_the_plane():
    cam = CAMERAS[0]
    px = (256.0, 400.0)
    assert back_project(cam, px).method == "plane"
    assert back_project(cam, px, depth=np.full((512, 512), 1.0)).method == "depth"


def test_letterboxed_answer_back_projects_through_the_original_camera():
    # the model answers in the 512 square; the goal comes from the 1280x720 frame's camera
    cam = CAMERAS[1]
    target = cam.point_on_plane(np.array([900.0, 650.0]))
    box = Letterbox.for_size(1280, 720)
    square = box.to_square(cam.project_pixels(target))
    goal = on_plane(cam, box.to_original(square))
    assert np.allclose(goal.point, target, atol=1e-9)


# -- generated frames -----------------------------------------------------------------------------
@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    """A one-house generated dataset with its depth maps (``_render/``), loaded, plus the house's
    ray caster (rebuilt from the same seed) to make GT points on rendered surfaces."""
    out = tmp_path_factory.mktemp("generated")
    generate_dataset(out, houses=1, seed=0, frames=3, progress=False, with_render=True)
    dataset = load_dataset(out)
    house_dir = out / "artifacts" / "train_house_00000"
    views = []  # (camera, depth map) of every exploration frame and observer view written
    for frame in dataset.instances(conditions=["a"])[0].frames:
        views.append((frame.camera, np.load(house_dir / "_render" / (Path(frame.image_path).stem + ".depth.npy"))))
    for inst in dataset.instances(conditions=["c"]):
        stem = Path(inst.frames[0].image_path).stem
        views.append((inst.frames[0].camera, np.load(house_dir / "_render" / f"{stem}.depth.npy")))
    return dataset, build_house(0, 0, shadows=False).renderer, views


def _surface_points(renderer, camera, n, seed):
    """GT points on rendered surfaces: rays through random sub-pixel positions, cast by embree."""
    rng = np.random.default_rng(seed)
    px = rng.uniform([0.0, 0.0], [camera.width, camera.height], size=(n, 2))
    dirs = camera.ray(px)
    _, t = renderer.cast(np.broadcast_to(np.asarray(camera.position), dirs.shape), dirs)
    keep = np.isfinite(t)
    return np.asarray(camera.position) + dirs[keep] * t[keep, None]


def _cell_spread(camera, depth, px):
    """How far the 3D points of the 3x3 pixel cells around ``px`` lie from the centre cell's:
    the depth map's resolution there."""
    col, row = int(px[0]), int(px[1])
    centre = camera.point_at_depth(np.array([col + 0.5, row + 0.5]), float(depth[row, col]))
    spread = 0.0
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            r, c = min(max(row + dr, 0), depth.shape[0] - 1), min(max(col + dc, 0), depth.shape[1] - 1)
            p = camera.point_at_depth(np.array([c + 0.5, r + 0.5]), float(depth[r, c]))
            spread = max(spread, float(np.linalg.norm(p - centre)))
    return spread


def test_oracle_pixel_back_projects_to_the_gt_point_within_the_depth_maps_resolution(generated):
    _, renderer, views = generated
    checked = 0
    for i, (cam, depth) in enumerate(views):
        for gt in _surface_points(renderer, cam, 60, seed=i):
            oracle = cam.project_pixels(gt)  # the geometry module's pixel for the GT point
            spread = _cell_spread(cam, depth, oracle)
            if not np.isfinite(spread) or spread > 0.25:
                continue  # a depth edge: the neighbouring cell sees another surface
            measured = float(depth[int(oracle[1]), int(oracle[0])])
            if abs(measured - cam.to_camera(gt)[2]) > spread + 0.01:
                continue  # a surface thinner than a pixel (a leg, a cord): the map cannot resolve it
            goal = back_project(cam, oracle, depth=depth)
            # the map is float16: its own rounding (2^-11 relative) adds to the cell spread
            tolerance = spread + 1e-3 * np.linalg.norm(gt - np.asarray(cam.position)) + 1e-4
            assert np.linalg.norm(np.array(goal.point) - gt) <= tolerance
            checked += 1
    assert checked > 150


def test_oracle_pixel_of_an_official_gt_back_projects_onto_its_height(generated):
    dataset, _, _ = generated
    checked = 0
    for inst in dataset.instances(conditions=["c"]):
        cam = inst.frames[0].camera
        oracle = cam.project_pixels(np.array(inst.target))
        if not np.all(np.isfinite(oracle)):
            continue
        try:
            goal = on_plane(cam, oracle, Plane.horizontal(inst.target[1]))
        except GoalUnavailable:
            continue  # the GT is above the camera: its height plane is met behind it
        assert np.allclose(goal.point, inst.target, atol=1e-9)
        checked += 1
    assert checked >= 3


def test_range_depth_map_gives_the_same_goals_as_the_z_depth_map(generated):
    _, _, views = generated
    cam, depth = views[0]
    depth = depth.astype(np.float64)
    v, u = np.mgrid[0 : cam.height, 0 : cam.width] + 0.5
    cos = 1.0 / np.linalg.norm(
        np.stack([(u - cam.width / 2) / cam.focal_px, (cam.height / 2 - v) / cam.focal_px, np.ones_like(u)]), axis=0
    )
    range_map = depth / cos
    for px in ([12.5, 300.5], [256.5, 256.5], [500.5, 480.5]):
        a = at_depth(cam, px, depth, depth_kind="z")
        b = at_depth(cam, px, range_map, depth_kind="range")
        assert np.allclose(a.point, b.point, atol=1e-9)
