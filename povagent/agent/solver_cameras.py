"""The robot's cameras for a strategy that solves the geometry itself (``geometric``), and its
3D answer brought back.

What it is for: a :class:`PosedSolver` is given each shown frame's camera instead of being told
nothing about them. Each camera (AI2-THOR's ``Camera`` or a ``PinholeCamera`` in any convention,
any intrinsics and frame size) is brought into the benchmark's world
(:class:`~povagent.geometry.solver_world.SolverWorld`: y up, the floor plane at ``y = 0``) and
onto the letterboxed square the model sees (:meth:`~povagent.geometry.goals.PinholeCamera.letterboxed`);
the 3D target it solves is mapped back into the robot's world (:func:`solved_goal`).

What it must not do: load frames or call a model; cameras that cannot be used together are a
:class:`~povagent.errors.BadInputError`, nothing is guessed.
"""

from __future__ import annotations

from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from povagent.dataset.instances import Instance
from povagent.dataset.release_models import Condition
from povagent.errors import BadInputError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.geometry.camera import Camera, ViewCamera
from povagent.geometry.goals import Goal3D, GoalCamera, PinholeCamera, Plane
from povagent.geometry.letterbox import Letterbox
from povagent.geometry.solver_world import SolverWorld
from povagent.interfaces import Ask


@runtime_checkable
class PosedSolver(Protocol):
    """A strategy that solves the geometry with the shown frames' cameras (``geometric``).

    ``solve_posed`` is :meth:`~povagent.interfaces.Strategy.solve` with one camera per shown
    image, describing that (letterboxed, square) image in the benchmark's world: y up, the floor
    at ``y = 0``, left-handed. A 3D target it works out (``Response.solved_point``) is in that
    world; the agent maps it back into the robot's.
    """

    async def solve_posed(
        self, instance: Instance, ask: Ask, images: ImageStore, cameras: Sequence[ViewCamera]
    ) -> list[tuple[Request, Response]]:
        """Every exchange, the final answer last."""
        ...


def posed_cameras(
    cameras: Sequence[GoalCamera | None], boxes: Sequence[Letterbox], floor: Plane, condition: Condition, unposed: Camera
) -> tuple[list[ViewCamera], SolverWorld | None]:
    """The robot's cameras as a :class:`PosedSolver` needs them: in the benchmark's world, on
    the letterboxed squares shown, and the world map they were brought in with.

    A/B triangulate with every frame's camera, so each frame needs one. C (the observer view)
    has no pose: without a camera the unposed square one stands in (only its field of view is
    read).
    """
    pinholes = [c if isinstance(c, PinholeCamera) or c is None else PinholeCamera.from_camera(c) for c in cameras]
    if condition.uses_exploration_frames:
        missing = [i for i, c in enumerate(pinholes) if c is None]
        if missing:
            raise BadInputError(
                f"cameras[{missing[0]}]: the geometric strategy triangulates with every frame's camera; "
                f"give one for each of the {len(pinholes)} frame(s) (or use another strategy)"
            )
    posed = [(i, c) for i, c in enumerate(pinholes) if c is not None]
    if not posed:
        return [unposed], None
    handed = {c.right_handed for _, c in posed}
    if len(handed) > 1:
        right = next(i for i, c in posed if c.right_handed)
        left = next(i for i, c in posed if not c.right_handed)
        raise BadInputError(
            f"cameras[{right}] is posed in a right-handed world but cameras[{left}] in a left-handed one "
            "(AI2-THOR's Camera is left-handed): give every camera in the same world"
        )
    world = SolverWorld.for_floor(floor, right_handed=handed.pop())
    solver: list[ViewCamera] = []
    for c, box in zip(pinholes, boxes):
        solver.append(unposed if c is None else c.moved(world.rotation, world.origin).letterboxed(box))
    return solver, world


def solved_goal(response: Response, camera: GoalCamera | None, world: SolverWorld | None, pixel: tuple[float, float]) -> Goal3D | None:
    """The 3D target a strategy worked out itself (``Response.solved_point``, in the solver's
    world), back in the robot's world; ``None`` when there is none."""
    point = response.solved_point
    if point is None or camera is None or world is None:
        return None
    x, y, z = (float(v) for v in world.to_world(np.asarray(point, dtype=float)))
    distance = float(np.linalg.norm(np.array([x, y, z]) - np.asarray(camera.position, dtype=float)))
    return Goal3D(point=(x, y, z), method="geometry", distance=distance, pixel=pixel)
