"""``sensor_msgs/CameraInfo`` to the intrinsics of a :class:`~povagent.geometry.goals.PinholeCamera`.

What is read: ``width``, ``height`` and ``K`` (row-major 3x3). ROS calibrations (like OpenCV's)
put pixel centres at whole numbers, so ``cx = K[2]`` is on pixel-index coordinates; povagent's
pixels are continuous (the centre of a ``W``-wide image is ``W/2``), so 0.5 is added to ``cx``
and ``cy`` here and nowhere else.

Lens distortion is REFUSED, not undistorted: a ``plumb_bob`` (or ``rational_polynomial``,
``equidistant``) calibration with any non-zero coefficient in ``D`` is a :class:`CameraProblem`
of kind ``distortion``. Feed the node the rectified stream (``image_rect_color``, whose
CameraInfo has ``D`` all zero, as ``image_proc`` publishes it): undistorting here would mean a
second, untested copy of OpenCV's model. Binning and a region of interest are refused too
(the intrinsics would no longer describe the image). Pure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from povagent.geometry.goals import PinholeCamera, PoseConvention


class CameraProblem(ValueError):
    """A calibration that cannot be used; ``kind`` is the counter it goes to."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


@dataclass(frozen=True)
class Intrinsics:
    """A checked calibration: focal lengths and principal point in continuous pixels, image size."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def camera(self, camera_to_map: np.ndarray, convention: PoseConvention | str = PoseConvention.OPENCV) -> PinholeCamera:
        """The camera with this calibration at ``camera_to_map`` (4x4, axes in ``convention``)."""
        return PinholeCamera(np.asarray(camera_to_map, dtype=float), self.fx, self.fy, self.cx, self.cy, self.width, self.height, PoseConvention(convention))

    def k_matrix(self) -> list[float]:
        """``K`` row-major as CameraInfo writes it (principal point back on pixel indices)."""
        return [self.fx, 0.0, self.cx - 0.5, 0.0, self.fy, self.cy - 0.5, 0.0, 0.0, 1.0]


def intrinsics_from_info(info: Any) -> Intrinsics:
    """The calibration of a ``CameraInfo``; :class:`CameraProblem` when it cannot be used."""
    width, height = int(info.width), int(info.height)
    if width < 1 or height < 1:
        raise CameraProblem("camera_info", f"camera_info of size {width}x{height}")
    k = [float(v) for v in info.k]
    if len(k) != 9 or not all(math.isfinite(v) for v in k):
        raise CameraProblem("camera_info", "camera_info K holds NaN or infinite values" if len(k) == 9 else f"camera_info K has {len(k)} values, not 9")
    fx, fy, cx, cy = k[0], k[4], k[2], k[5]
    if fx <= 0 or fy <= 0:
        raise CameraProblem("camera_info", f"camera_info K has non-positive focal lengths fx={fx:g}, fy={fy:g} (an uncalibrated camera publishes zeros)")
    if k[1] != 0.0 or k[3] != 0.0 or k[6:] != [0.0, 0.0, 1.0]:
        raise CameraProblem("camera_info", "camera_info K is not a pinhole matrix [fx 0 cx; 0 fy cy; 0 0 1] (skew is not supported)")
    d = [float(v) for v in getattr(info, "d", ())]
    if not all(math.isfinite(v) for v in d):
        raise CameraProblem("camera_info", "camera_info D holds NaN or infinite values")
    if any(v != 0.0 for v in d):
        model = str(getattr(info, "distortion_model", "") or "unnamed")
        raise CameraProblem(
            "distortion",
            f"camera_info has {model} distortion (D non-zero): distortion is refused, not undistorted; subscribe to the rectified image (image_rect_color)",
        )
    if int(getattr(info, "binning_x", 0)) > 1 or int(getattr(info, "binning_y", 0)) > 1:
        raise CameraProblem("camera_info", "camera_info with binning is not supported")
    roi = getattr(info, "roi", None)
    if roi is not None and (int(roi.width) not in (0, width) or int(roi.height) not in (0, height)):
        raise CameraProblem("camera_info", "camera_info with a region of interest is not supported")
    return Intrinsics(fx, fy, cx + 0.5, cy + 0.5, width, height)


__all__ = ["CameraProblem", "Intrinsics", "intrinsics_from_info"]
