"""CameraInfo to a PinholeCamera's intrinsics: K read, pixel-index principal point moved to
continuous pixels, distortion refused."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from povagent.ros.camera_info import CameraProblem, intrinsics_from_info


def info(**changes) -> SimpleNamespace:
    base = dict(width=640, height=480, k=[500.0, 0, 319.5, 0, 510.0, 239.5, 0, 0, 1], d=[], distortion_model="plumb_bob",
                binning_x=0, binning_y=0, roi=SimpleNamespace(width=0, height=0))
    base.update(changes)
    return SimpleNamespace(**base)


def test_k_gives_focal_lengths_and_the_principal_point_on_continuous_pixels():
    i = intrinsics_from_info(info())
    assert (i.fx, i.fy, i.cx, i.cy, i.width, i.height) == (500.0, 510.0, 320.0, 240.0, 640, 480)


def test_the_camera_projects_its_optical_axis_to_the_principal_point():
    cam = intrinsics_from_info(info()).camera(np.eye(4))
    assert np.allclose(cam.project_pixels(np.array([[0.0, 0.0, 2.0]])), [[320.0, 240.0]])


def test_k_written_back_is_the_k_read():
    assert intrinsics_from_info(info()).k_matrix() == pytest.approx(info().k)


def test_plumb_bob_with_nonzero_d_is_refused_not_undistorted():
    with pytest.raises(CameraProblem, match=r"plumb_bob distortion .*refused, not undistorted.*image_rect") as exc:
        intrinsics_from_info(info(d=[0.1, -0.05, 0.0, 0.0, 0.0]))
    assert exc.value.kind == "distortion"


def test_plumb_bob_with_all_zero_d_is_a_rectified_camera():
    assert intrinsics_from_info(info(d=[0.0] * 5)).fx == 500.0


@pytest.mark.parametrize(("change", "message"), [
    ({"k": [float("nan")] * 9}, "NaN"),
    ({"k": [0.0] * 9}, "non-positive focal"),
    ({"k": [500.0, 0, 319.5]}, "3 values"),
    ({"width": 0}, "size 0x480"),
    ({"k": [500.0, 2.0, 319.5, 0, 510.0, 239.5, 0, 0, 1]}, "skew"),
    ({"binning_x": 2}, "binning"),
    ({"roi": SimpleNamespace(width=320, height=240)}, "region of interest"),
])
def test_an_unusable_calibration_is_a_camera_info_problem(change, message):
    with pytest.raises(CameraProblem, match=message) as exc:
        intrinsics_from_info(info(**change))
    assert exc.value.kind == "camera_info"
