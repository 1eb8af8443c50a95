"""The benchmark's world the geometric solver reasons in, and a robot's world mapped into it.

The solver places targets by the benchmark's own rules (:mod:`povagent.geometry.ground_truth`),
written for AI2-THOR's world: y up, the floor at ``y = 0``, left-handed (an observer's right is
``up x forward``); its size priors are heights above that floor. A robot's world is usually
ROS's ``map``: z up, right-handed, the floor at ``z = 0`` or wherever it is.

:class:`SolverWorld` is the rigid map ``p' = rotation (p - origin)`` from a robot's world into
the solver's, fixed by the floor plane (its normal is up, its point the floor's height) and the
world's handedness (a rigid pose's determinant says it: +1 right-handed, -1 Unity). The
horizontal axes are the robot world's own as far as possible (for a z-up world: x stays x, y
becomes z), so furniture aligned with the robot's map stays aligned with the solver's axes, as
the benchmark's axis-aligned boxes assume. Points go back with :meth:`SolverWorld.to_world`.
Pure: numbers in, numbers out.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from povagent.geometry.goals import Plane


@dataclass(frozen=True)
class SolverWorld:
    """``p_solver = rotation (p_world - origin)``; ``rotation``'s rows are the solver's x, y (up)
    and z axes written in the robot's world."""

    rotation: np.ndarray = field(repr=False)
    origin: np.ndarray = field(repr=False)

    @classmethod
    def for_floor(cls, floor: Plane, right_handed: bool) -> SolverWorld:
        """The solver's world for a robot world with this ``floor`` (normal pointing up) and handedness.

        AI2-THOR's own world (``floor`` ``y = 0``, left-handed) maps to itself exactly.
        """
        up = np.asarray(floor.normal, dtype=float)
        up = up / np.linalg.norm(up)
        # the robot's axis most nearly horizontal becomes the solver's x (the first on a tie)
        axis = np.eye(3)[int(np.argmin(np.abs(up)))]
        x = axis - (axis @ up) * up
        x = x / np.linalg.norm(x)
        z = np.cross(up, x)
        rotation = np.stack([x, up, z])
        # the solver's world is left-handed: a reflection for a right-handed robot world
        wanted = -1.0 if right_handed else 1.0
        if np.sign(np.linalg.det(rotation)) != wanted:
            rotation[2] = -rotation[2]
        return cls(rotation, np.asarray(floor.point, dtype=float))

    def to_solver(self, points: np.ndarray) -> np.ndarray:
        """Robot-world points ``(..., 3)`` in the solver's world."""
        return (np.asarray(points, dtype=float) - self.origin) @ self.rotation.T

    def to_world(self, points: np.ndarray) -> np.ndarray:
        """Solver-world points ``(..., 3)`` back in the robot's world."""
        return np.asarray(points, dtype=float) @ self.rotation + self.origin
