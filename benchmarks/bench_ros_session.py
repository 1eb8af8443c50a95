"""How fast the ROS session takes camera images, idle and while a command is being answered.

The node's subscriptions and ``ros-replay`` feed one :class:`~povagent.ros.session.GroundingSession`;
this measures that path without DDS: 640x480 ``rgb8`` images with their ``CameraInfo`` and a
``nav_msgs/Odometry`` each, from a robot driving a circle of 3 m radius at 0.5 m/s with a camera
at 30 Hz (so the keyframe memory fills to 30 and its coverage eviction runs). Messages are plain
objects with the ROS field names (what rclpy and rosbags hand over). Two passes over the same
messages: idle, and while another thread answers a command whose model call takes 2 s of wall
time (a remote model: the answering thread waits on I/O, as the node's worker does).

Each pass is timed in CPU time (``time.process_time``: every thread of the process, so the
answering thread's own work counts against the busy pass) as well as wall time: under load the
wall-clock rate measures the machine's other work (a published 166 images/s was a loaded
machine's; the CPU figure is what reproduces), so the CPU milliseconds per image and the rate
they allow are the figures, with the load average beside them. Prints the intake rates and
their ratios to a 30 Hz camera and to each other; writes ``benchmarks/results/bench_ros_session.json``.

    python benchmarks/bench_ros_session.py [--images 1200]
"""

from __future__ import annotations

import argparse
import math
import os
import threading
import time
from types import SimpleNamespace

import numpy as np
from results_file import record

from povagent.ros.camera_info import Intrinsics
from povagent.ros.session import GroundingSession
from povagent.ros.transforms import RigidTransform

CAMERA_HZ = 30.0
W, H = 640, 480
S = 1_000_000_000


def header(ns: int, frame: str) -> SimpleNamespace:
    return SimpleNamespace(stamp=SimpleNamespace(sec=ns // S, nanosec=ns % S), frame_id=frame)


def messages(n: int) -> list[tuple[SimpleNamespace, SimpleNamespace, SimpleNamespace]]:
    """(odometry, camera_info, image) per frame of the drive."""
    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 255, size=(H, W, 3), dtype=np.uint8).tobytes()
    k = Intrinsics(500.0, 500.0, 320.0, 240.0, W, H).k_matrix()
    out = []
    for i in range(n):
        ns = 100 * S + int(i * S / CAMERA_HZ)
        angle = 0.5 / 3.0 * i / CAMERA_HZ  # 0.5 m/s on a 3 m circle
        yaw = angle + math.pi / 2
        pose = SimpleNamespace(position=SimpleNamespace(x=3 * math.cos(angle), y=3 * math.sin(angle), z=0.0),
                               orientation=SimpleNamespace(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)))
        odom = SimpleNamespace(header=header(ns, "map"), child_frame_id="base_link", pose=SimpleNamespace(pose=pose))
        info = SimpleNamespace(header=header(ns, "cam_optical_frame"), width=W, height=H, k=k, d=[], distortion_model="plumb_bob",
                               binning_x=0, binning_y=0, roi=SimpleNamespace(width=0, height=0))
        image = SimpleNamespace(header=header(ns, "cam_optical_frame"), height=H, width=W, encoding="rgb8", step=W * 3, is_bigendian=0, data=pixels)
        out.append((odom, info, image))
    return out


def remote_model(seconds: float):
    def locate(sentence, frames, cameras, depths):
        time.sleep(seconds)  # waiting on the network, as a hosted model's call does
        raise TimeoutError("the benchmark's model never answers")

    return locate


def intake(session: GroundingSession, msgs) -> tuple[float, float]:
    """``(CPU seconds per image, wall-clock images per second)`` taken by ``session``."""
    start, cpu = time.perf_counter(), time.process_time()
    for odom, info, image in msgs:
        session.on_odometry(odom)
        session.on_camera_info(info)
        session.on_image(image)
    return (time.process_time() - cpu) / len(msgs), len(msgs) / (time.perf_counter() - start)


def new_session(answer_s: float) -> GroundingSession:
    s = GroundingSession(remote_model(answer_s))
    s.add_static("base_link", "cam_optical_frame", RigidTransform((0.0, 0.0, 0.9), (-0.5, 0.5, -0.5, 0.5)))
    return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--images", type=int, default=1200, help="images per pass (30 Hz stamps)")
    args = ap.parse_args()
    msgs = messages(args.images)

    idle_session = new_session(2.0)
    idle_cpu, idle_wall = intake(idle_session, msgs)
    idle = 1 / idle_cpu

    busy_session = new_session(2.0)
    done = threading.Event()

    def answer_forever() -> None:
        while not done.is_set():
            try:
                busy_session.answer("the mug right of the kettle")
            except TimeoutError:
                pass

    worker = threading.Thread(target=answer_forever, daemon=True)
    for odom, info, image in msgs[:1]:  # one keyframe, so the answer reaches the model call
        busy_session.on_odometry(odom)
        busy_session.on_camera_info(info)
        busy_session.on_image(image)
    worker.start()
    time.sleep(0.1)
    busy_cpu, busy_wall = intake(busy_session, msgs[1:])
    busy = 1 / busy_cpu
    done.set()
    load = os.getloadavg()

    kept = len(idle_session.memory)
    print(f"idle:      {1000 * idle_cpu:.2f} ms CPU an image = {idle:8.1f} images per CPU-second ({idle / CAMERA_HZ:.1f}x a "
          f"{CAMERA_HZ:g} Hz camera; wall clock {idle_wall:.1f}/s), {kept} keyframes kept of {len(msgs)}")
    print(f"answering: {1000 * busy_cpu:.2f} ms CPU an image = {busy:8.1f} images per CPU-second ({busy / idle:.2f}x idle; "
          f"wall clock {busy_wall:.1f}/s) while a 2 s model call runs")
    print(f"load average: {load}")
    figures = [
        {"name": "session intake CPU per image, idle", "value": round(1000 * idle_cpu, 3), "unit": "ms", "target": "",
         "comparison": f"640x480 rgb8 with CameraInfo and odometry; wall clock under load {round(idle_wall, 1)} images/s"},
        {"name": "session intake, idle", "value": round(idle, 1), "unit": "images per CPU-second", "target": f">= {CAMERA_HZ:g} (one camera)",
         "comparison": f"a {CAMERA_HZ:g} Hz 640x480 rgb8 camera"},
        {"name": "session intake over camera rate", "value": round(idle / CAMERA_HZ, 2), "unit": "x", "target": ">= 1",
         "comparison": f"{CAMERA_HZ:g} Hz, 640x480 rgb8, odometry per image, max_frames 30"},
        {"name": "intake while answering over idle", "value": round(busy / idle, 2), "unit": "x", "target": ">= 0.9",
         "comparison": "the same messages with no command being answered; the model call waits 2 s on I/O"},
    ]
    print(f"wrote {record('bench_ros_session', figures, f'python benchmarks/bench_ros_session.py --images {args.images}')}")


if __name__ == "__main__":
    main()
