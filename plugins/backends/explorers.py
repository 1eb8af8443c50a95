"""Offline explorers for the active mode: ``explorer-oracle`` and ``explorer-random``.

They answer the ``active`` strategy's requests with tool calls, as a model would, reading the
episode's state from ``Request.question`` (the poses of the frames shown and of every view so
far) and, for the oracle, the ground truth from the instance. They anchor the active numbers:

* ``explorer-oracle``: goes to the shown frame nearest the speaker's standpoint, moves to the
  observer's position (at robot height; a move stops at furniture), turns to the observer's
  heading (or, when that heading leaves the target outside the view, towards the target) and
  tilts to look at the target, then answers the ground truth projected into that last view.
  Its official L2 is ~0: an end-to-end check of poses, rendering, records and scoring.
* on the navigate task (the request offers ``arrived``), ``explorer-oracle`` walks the
  geodesic shortest path to where the target is reached and seen (each move the longest
  straight stretch of it the floor allows, so it never walks farther than the path), turns and
  tilts to the target and calls ``arrived``: SPL ~1, success 100%.
* ``explorer-random``: random actions (seeded by instance, run and step) until the budget is
  spent, then the centre of the last view (on the navigate task: ``arrived`` where it stands). Its actions are the tools the request offers that
  declare how a random explorer calls them (:attr:`povagent.active.tools.Tool.explore`), so a
  plugin's tool is explored like the built-ins.

Neither calls a network or is cached, and neither reads files, but the oracle on the navigate
task rebuilds the house it walks (:func:`povagent.active.navigation.house_of`). A request without tools (a passive
strategy) is refused: these backends only explore.
"""

from __future__ import annotations

import asyncio
import json
import math
from typing import Any, ClassVar, Mapping

from povagent import hookimpl
from povagent.dataset.instances import Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, ToolCall, Usage
from povagent.geometry.camera import Camera
from povagent.interfaces import Backend, PermanentBackendError
from povagent.plugins import get_plugin_host
from povagent.scoring.normalized_l2 import project_ground_truth
from povagent_plugins.backends.baselines import request_run, seeded_rng

#: Half the field of view kept clear around the target when the oracle turns (degrees).
_IN_VIEW = 40.0
#: How near (m) the oracle's walk must be to the shortest path's end to stop walking.
_THERE = 0.01


def _camera(record: Mapping[str, Any]) -> Camera:
    return Camera((record["x"], record["y"], record["z"]), record["yaw"], record["horizon"], record["fov"], record["width"], record["height"])


def _calls(request: Request, *calls: tuple[str, dict[str, Any]]) -> Response:
    state = request.question or {}
    base = len(state.get("views", ())) + len(state.get("actions", ()))
    tool_calls = tuple(ToolCall(f"call_{base}_{k}", name, json.dumps(args)) for k, (name, args) in enumerate(calls))
    return Response(text="", usage=Usage(0, 0, 0.0), tool_calls=tool_calls)


def _state(request: Request, name: str) -> Mapping[str, Any]:
    state = request.question
    if not request.tools or not isinstance(state, Mapping) or state.get("kind") != "active":
        raise PermanentBackendError(f"backend {name!r} answers the active strategy's requests only (strategy: active)")
    return state


def _offered(request: Request) -> set[str]:
    return {t["function"]["name"] for t in request.tools}


def _answer_centre(request: Request, state: Mapping[str, Any]) -> Response:
    if "arrived" in _offered(request):  # the navigate task: the answer is where it stands
        return _calls(request, ("arrived", {}))
    views = state.get("views", [])
    cam = views[-1]["camera"] if views else state["frames"][0]
    image = f"view {views[-1]['n']}" if views else "frame 0"
    return _calls(request, ("answer", {"image": image, "x": cam["width"] / 2, "y": cam["height"] / 2}))


class ExplorerOracle(Backend):
    """Walks to the observer's standpoint and answers the ground truth in the view it sees."""

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True

    def identity(self) -> Mapping[str, Any]:
        """Name only: it has no options."""
        return {"backend": "explorer-oracle"}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """The next step of the oracle's walk, from the episode's state."""
        state = _state(request, "explorer-oracle")
        instance = request.instance
        if instance is None:
            raise PermanentBackendError("explorer-oracle needs the instance (its ground truth)")
        actions, views, left = list(state.get("actions", [])), state.get("views", []), int(state.get("budget_left", 0))
        if "arrived" in _offered(request):
            return await asyncio.to_thread(self._walk, request, state, instance)
        obs = instance.observer_camera
        ox, oz = float(obs.position[0]), float(obs.position[2])
        pose = state["pose"]
        if left > 0 and not views:
            frames = state["frames"]
            nearest = min(range(len(frames)), key=lambda k: (frames[k]["x"] - ox) ** 2 + (frames[k]["z"] - oz) ** 2)
            return _calls(request, ("go_to_frame", {"frame": nearest}))
        if left > 0 and "move" not in actions and math.hypot(pose["x"] - ox, pose["z"] - oz) > 0.05:
            dx, dz = ox - pose["x"], oz - pose["z"]
            yaw = math.radians(pose["yaw"])
            fx, fz = math.sin(yaw), math.cos(yaw)
            return _calls(request, ("move", {"forward": dx * fx + dz * fz, "right": dx * fz - dz * fx}))
        if left >= 2 and "turn" not in actions:
            return _calls(request, *self._look(pose, float(obs.yaw), instance.target))
        cam = _camera(views[-1]["camera"]) if views else _camera(state["frames"][0])
        gt = project_ground_truth(instance.target, cam)
        x = min(cam.width - 1.0, max(0.0, gt.u * cam.width))
        y = min(cam.height - 1.0, max(0.0, gt.v * cam.height))
        image = f"view {views[-1]['n']}" if views else "frame 0"
        return _calls(request, ("answer", {"image": image, "x": round(x, 3), "y": round(y, 3)}))

    def _walk(self, request: Request, state: Mapping[str, Any], instance: Instance) -> Response:
        """The navigate task: the longest straight move along the shortest arrival path, and
        once there, turn and tilt to the target and call ``arrived``."""
        from povagent.active.navigation import house_floor, house_of, shortest_arrival

        pose, left = state["pose"], int(state.get("budget_left", 0))
        house = house_of(instance)
        floor, _ = house_floor(house)
        plan = shortest_arrival(house, (pose["x"], pose["z"]), instance.target)
        if plan is not None and left > 2 and plan.length > _THERE:
            for px, pz in reversed(plan.points[1:]):  # the farthest point of the path one move reaches
                dx, dz = px - pose["x"], pz - pose["z"]
                if not floor.move(pose["x"], pose["z"], dx, dz).blocked:
                    break
            yaw = math.radians(pose["yaw"])
            fx, fz = math.sin(yaw), math.cos(yaw)
            return _calls(request, ("move", {"forward": round(dx * fx + dz * fz, 4), "right": round(dx * fz - dz * fx, 4)}))
        bearing = math.degrees(math.atan2(instance.target[0] - pose["x"], instance.target[2] - pose["z"])) % 360.0
        looks = self._look(pose, bearing, instance.target) if left >= 2 else []
        return _calls(request, *looks, ("arrived", {}))

    @staticmethod
    def _look(pose: Mapping[str, Any], observer_yaw: float, target: tuple[float, float, float]) -> list[tuple[str, dict[str, Any]]]:
        """Turn to the observer's heading (or to the target when that leaves it out of view), tilt to it."""
        dx, dz = target[0] - pose["x"], target[2] - pose["z"]
        bearing = math.degrees(math.atan2(dx, dz)) % 360.0
        off = (bearing - observer_yaw + 180.0) % 360.0 - 180.0
        yaw = observer_yaw if abs(off) <= _IN_VIEW else bearing
        turn = (yaw - pose["yaw"] + 180.0) % 360.0 - 180.0
        horizon = math.degrees(math.atan2(pose["y"] - target[1], math.hypot(dx, dz)))
        return [("turn", {"degrees": round(turn, 3)}), ("tilt", {"degrees": round(horizon - pose["horizon"], 3)})]


class ExplorerRandom(Backend):
    """Random actions until the budget is spent, then the centre of the last view."""

    cacheable: ClassVar[bool] = False
    offline_baseline: ClassVar[bool] = True

    def __init__(self, seed: int = 0) -> None:
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ValueError(f"explorer-random option seed must be an integer, got {seed!r}")
        self.seed = seed

    def identity(self) -> Mapping[str, Any]:
        """Name and seed."""
        return {"backend": "explorer-random", "seed": self.seed}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """One random action, or the answer once the budget is spent."""
        state = _state(request, "explorer-random")
        if int(state.get("budget_left", 0)) <= 0:
            return _answer_centre(request, state)
        instance = request.instance.id if request.instance is not None else ""
        rng = seeded_rng(self.seed, instance, request_run(request), len(state.get("actions", [])))
        registered = get_plugin_host().tools(None).tools
        offered = [t["function"]["name"] for t in request.tools]
        choices = [(n, explore) for n in offered if n in registered and (explore := registered[n].explore) is not None]
        if not choices:
            return _answer_centre(request, state)
        name, explore = rng.choice(choices)
        return _calls(request, (name, explore(rng, state)))


@hookimpl
def register_backends(register) -> None:
    """Contribute the two offline explorers."""
    register("explorer-oracle", ExplorerOracle, description="Active mode: walks to the observer's standpoint, answers the GT (L2 ~ 0)")
    register("explorer-random", ExplorerRandom, description="Active mode: random actions within the budget, then the last view's centre")
