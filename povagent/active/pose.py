"""Where the robot stands and looks: a pose, the camera it gives, and how tools change it.

What it is for: the tools speak in the robot's terms (turn right by degrees, tilt down, move
forward and right in metres); the renderer and the scorer speak in AI2-THOR cameras. A
:class:`Pose` is the one bridge: yaw grows clockwise seen from above (as ``cam_yaw``), the
horizon grows looking down and is clamped to the robot's range, and the pose describes itself
in words relative to where the episode started. Pure: no rendering, no floor (``floor.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from povagent.geometry.camera import Camera

#: The robot camera's height (m), as the exploration frames were taken.
ROBOT_CAMERA_HEIGHT = 0.9
#: The horizon range a tilt is clamped to (degrees, positive looks down).
HORIZON_RANGE = (-30.0, 60.0)
#: Decimals kept in a pose (0.1 mm, 0.001 degree): a pose written to a row reads back the same.
POSITION_DECIMALS = 4
ANGLE_DECIMALS = 3


@dataclass(frozen=True)
class Pose:
    """The camera's position (x, y, z), yaw and horizon (degrees), fov and image size."""

    x: float
    y: float
    z: float
    yaw: float
    horizon: float
    fov: float = 100.0
    width: int = 512
    height: int = 512

    @classmethod
    def of_camera(cls, camera: Camera) -> Pose:
        """The pose of a dataset camera (an exploration frame's or an observer view's)."""
        x, y, z = (float(v) for v in camera.position)
        return cls(x, y, z, float(camera.yaw), float(camera.horizon), float(camera.fov), camera.width, camera.height)

    def camera(self) -> Camera:
        """The AI2-THOR camera of this pose."""
        return Camera((self.x, self.y, self.z), self.yaw, self.horizon, self.fov, self.width, self.height)

    def turned(self, degrees: float) -> Pose:
        """Rotated in place; positive turns right (clockwise seen from above)."""
        return replace(self, yaw=round((self.yaw + degrees) % 360.0, ANGLE_DECIMALS) % 360.0)

    def tilted(self, degrees: float) -> Pose:
        """Tilted; positive looks further down, the result clamped to :data:`HORIZON_RANGE`."""
        lo, hi = HORIZON_RANGE
        return replace(self, horizon=round(min(hi, max(lo, self.horizon + degrees)), ANGLE_DECIMALS))

    def heading(self) -> tuple[float, float]:
        """The unit forward direction on the floor, (dx, dz)."""
        r = math.radians(self.yaw)
        return math.sin(r), math.cos(r)

    def offset(self, forward: float, right: float) -> tuple[float, float]:
        """The floor displacement (dx, dz) of ``forward`` and ``right`` metres in this heading."""
        fx, fz = self.heading()
        # right = (cos y, -sin y) = (fz, -fx)
        return forward * fx + right * fz, forward * fz - right * fx

    def moved_to(self, x: float, z: float) -> Pose:
        """The same heading at floor position (x, z)."""
        return replace(self, x=round(x, POSITION_DECIMALS), z=round(z, POSITION_DECIMALS))

    def record(self) -> dict[str, float | int]:
        """The pose as rows store it (the camera fields, scoring-ready)."""
        return {"x": self.x, "y": self.y, "z": self.z, "yaw": self.yaw, "horizon": self.horizon, "fov": self.fov, "width": self.width, "height": self.height}

    def in_words(self, start: Pose) -> str:
        """Where this pose is relative to ``start``: metres forward/right of it, degrees turned, tilt."""
        dx, dz = self.x - start.x, self.z - start.z
        fx, fz = start.heading()
        ahead, right = dx * fx + dz * fz, dx * fz - dz * fx
        turn = (self.yaw - start.yaw + 180.0) % 360.0 - 180.0
        side = "right" if turn >= 0 else "left"
        return (
            f"{ahead:+.2f} m forward and {right:+.2f} m right of the start, turned {abs(turn):.0f} degrees "
            f"{side} of the start heading, looking {abs(self.horizon):.0f} degrees "
            f"{'down' if self.horizon >= 0 else 'up'}"
        )
