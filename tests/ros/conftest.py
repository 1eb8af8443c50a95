"""Shared fixtures of the ROS tests: a generated house as a tour, a simulated model, a ROS 2 graph.

The graph is real (rclpy, Fast DDS) and stays on this machine: every test that starts ROS 2 runs
in a context whose environment says ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and whose
``ROS_DOMAIN_ID`` is this process's own (derived from the pid, within 0-101), and the context is
shut down at the end of the session.
"""

from __future__ import annotations

import os
import struct
import time
import zlib
from typing import Any, Callable, Iterator

import pytest

from povagent.agent import GroundingAgent
from povagent.dataset.loader import load_dataset
from povagent.geometry.goals import Plane
from povagent.ros.house_tour import HouseTour, house_tour, well_seen_instance
from povagent.ros.session import Locate

MAP_FLOOR = Plane.horizontal(0.0, up_axis="z")


@pytest.fixture(scope="session")
def tour(generated_release) -> HouseTour:
    """The first well-seen Inferred instance of the generated set, as a robot's tour."""
    found = well_seen_instance(load_dataset(generated_release))
    assert found is not None
    return house_tour(*found)


@pytest.fixture(scope="session")
def simulated_locate(tour: HouseTour) -> Locate:
    """The geometric agent with SIMULATED exact perception of the tour's house (not a model):
    the simulator sees the scene through the cameras the agent is given."""
    from povagent_plugins.backends.simulated import SimulatedScene

    truth = tour.truth

    def locate(sentence, frames, cameras, depths):
        scene = SimulatedScene(truth.objects, cameras, anchor=truth.anchor, observer=truth.observer, direction=truth.direction, surface=truth.surface)
        with GroundingAgent(backend=scene, strategy="geometric", parser="json", plane=MAP_FLOOR) as agent:
            return agent.locate(sentence, list(frames), cameras=list(cameras))

    return locate


def _wait_until(condition: Callable[[], Any], timeout: float = 20.0, what: str = "condition") -> Any:
    """Poll ``condition`` until it is truthy; fail naming ``what`` after ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")


@pytest.fixture(scope="session")
def wait_until() -> Callable[..., Any]:
    """``wait_until(condition, timeout=20, what=...)``: poll until truthy, else fail naming ``what``."""
    return _wait_until


def _claimed_png(width: int, height: int) -> bytes:
    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8-bit RGB
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\x00" * 64))


@pytest.fixture(scope="session")
def claimed_png() -> Callable[[int, int], bytes]:
    """``claimed_png(width, height)``: a PNG that claims that many RGB pixels and holds a few bytes
    of them, so any attempt to decode it fails: only a check made before decoding names its size."""
    return _claimed_png


@pytest.fixture(scope="session")
def ros_graph(tmp_path_factory) -> Iterator[Any]:
    """A real rclpy context on loopback with this process's own domain id; a background executor
    spins every node added to it. Yields an object with ``context``, ``add(node)``, ``remove(node)``."""
    keys = ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_DOMAIN_ID", "ROS_LOG_DIR")
    saved = {k: os.environ.get(k) for k in keys}
    # 40-99: clear of the default 0 and of other sessions' pids; under pytest-xdist each worker
    # (gw0-gw3: the README's command runs at most four) keeps its own residue mod 4, so two
    # workers of one session never share a graph
    worker = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw") or 0) % 4
    domain = 40 + (os.getpid() % 15) * 4 + worker
    os.environ.update({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_DOMAIN_ID": str(domain), "ROS_LOG_DIR": str(tmp_path_factory.mktemp("ros-log"))})
    from povagent.ros.extras import require_rclpy

    rclpy = require_rclpy("the ROS tests")
    from rclpy.executors import MultiThreadedExecutor

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    from povagent.ros.spinning import BackgroundSpin

    executor = MultiThreadedExecutor(num_threads=2, context=context)
    spinning = BackgroundSpin(executor, name="ros-test-executor").start()

    class Graph:
        def __init__(self) -> None:
            self.context = context
            self.domain = domain

        def add(self, node: Any) -> Any:
            executor.add_node(node)
            return node

        def remove(self, node: Any) -> None:
            """Take ``node`` out of the executor; it may be destroyed once this returns."""
            executor.remove_node(node)
            spinning.settle()

    try:
        yield Graph()
    finally:
        spinning.stop()  # the executor first (its thread joined), then the context
        rclpy.shutdown(context=context)
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v

