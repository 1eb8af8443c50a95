"""A robot app embedding povagent's GroundingAgent: frames + a user's sentence -> a 3D goal.

Runs offline as is (the ``center`` baseline answers instead of a model)::

    python examples/robot_app.py

With a real model, pass a pipeline YAML (the same file a benchmark run takes) or a model::

    python examples/robot_app.py --pipeline my_pipeline.yaml
    OPENAI_API_KEY=... python examples/robot_app.py --model openai/gpt-5.4

The robot here is a ROS-style one: its world frame is z-up (``map``), its camera poses are 4x4
camera-to-world matrices in the OpenCV optical convention (x right, y down, z forward), and its
frames are 1280x720. The frames are drawn procedurally so the example needs no files; a real
app passes its own images (paths, PIL images or numpy RGB arrays) and poses.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np
from PIL import Image, ImageDraw

from povagent.agent import GroundingAgent
from povagent.errors import BadInputError, GroundingError, NoAnswerError, PovagentError, UnparseableAnswerError
from povagent.geometry.goals import PinholeCamera, Plane

WIDTH, HEIGHT = 1280, 720
CAMERA_HEIGHT_M = 1.0
CAMERA_TILT_DEG = 25.0  # looking down
VERTICAL_FOV_DEG = 58.0


def camera_pose(x: float, y: float, heading_deg: float) -> np.ndarray:
    """4x4 camera-to-world pose (OpenCV optical axes) of the robot's head camera in a z-up map."""
    h, t = math.radians(heading_deg), math.radians(CAMERA_TILT_DEG)
    forward_flat = np.array([math.cos(h), math.sin(h), 0.0])
    left = np.array([-math.sin(h), math.cos(h), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    forward = math.cos(t) * forward_flat - math.sin(t) * up  # tilted down
    down = np.cross(forward, -left)  # completes a right-handed (right, down, forward) frame
    right = -left
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = right, down, forward
    pose[:3, 3] = (x, y, CAMERA_HEIGHT_M)
    return pose


def draw_room(seed: int) -> Image.Image:
    """A stand-in for a camera frame: floor, wall and a few pieces of 'furniture'."""
    rng = np.random.default_rng(seed)
    im = Image.new("RGB", (WIDTH, HEIGHT), (200, 196, 186))
    d = ImageDraw.Draw(im)
    d.rectangle([0, HEIGHT * 0.45, WIDTH, HEIGHT], fill=(150, 118, 84))  # floor
    for _ in range(4):
        x0, y0 = rng.uniform(0, WIDTH - 200), rng.uniform(HEIGHT * 0.3, HEIGHT * 0.7)
        w, h = rng.uniform(80, 260), rng.uniform(60, 200)
        colour = tuple(int(c) for c in rng.integers(30, 230, 3))
        d.rectangle([x0, y0, x0 + w, y0 + h], fill=colour, outline=(20, 20, 20), width=3)
    return im


def main(argv: list[str] | None = None) -> int:
    """Locate one command in three frames and print the frame, the pixel and the 3D goal."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pipeline", help="pipeline YAML (backend/model, strategy, parser, timeout)")
    ap.add_argument("--model", help="a litellm model string or profile name, e.g. openai/gpt-5.4")
    ap.add_argument("--sentence", default="While I was cooking, I left my phone to the right of the kettle.")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds for the whole call, retries included")
    ap.add_argument(
        "--strategy",
        default="basic",
        help="how the model is asked: 'basic', or 'geometric' (the model reads the sentence and points, the "
        "geometry is solved; with cameras in AI2-THOR's convention, povagent.geometry.camera.Camera, the goal is "
        "the solved 3D target itself, method 'geometry')",
    )
    args = ap.parse_args(argv)

    # The robot's memory of its tour: frames and where its camera was for each.
    frames = [draw_room(seed) for seed in range(3)]
    poses = [camera_pose(0.0, 0.0, 0.0), camera_pose(2.0, 0.5, 90.0), camera_pose(2.5, 3.0, 200.0)]
    cameras = [PinholeCamera.from_fov(p, VERTICAL_FOV_DEG, WIDTH, HEIGHT, convention="opencv") for p in poses]
    floor = Plane.horizontal(0.0, up_axis="z")  # ROS map: z up, floor at z = 0

    try:
        if args.pipeline:
            agent = GroundingAgent.from_pipeline(args.pipeline, plane=floor, timeout_s=args.timeout)
        elif args.model:
            agent = GroundingAgent(model=args.model, strategy=args.strategy, plane=floor, timeout_s=args.timeout)  # a profile or litellm string
        else:
            agent = GroundingAgent("center", strategy=args.strategy, plane=floor, timeout_s=args.timeout)  # offline baseline
    except PovagentError as exc:  # a bad pipeline file, an unknown plugin name, a missing option
        print(f"error: {exc}", file=sys.stderr)
        return 1

    with agent:
        try:
            loc = agent.locate(args.sentence, frames, cameras=cameras)
        except BadInputError as exc:
            print(f"bad input: {exc}", file=sys.stderr)
            return 2
        except UnparseableAnswerError as exc:
            print(f"the model answered, but not with a point: {exc}", file=sys.stderr)
            return 3
        except NoAnswerError as exc:
            print(f"no answer (retry later or fall back): {exc}", file=sys.stderr)
            return 4
        except GroundingError as exc:
            print(f"grounding failed: {exc}", file=sys.stderr)
            return 5

    print(f"sentence: {args.sentence}")
    print(f"frame:    {loc.frame_index} of {len(frames)} ({loc.frame_size[0]}x{loc.frame_size[1]})")
    print(f"pixel:    ({loc.pixel[0]:.1f}, {loc.pixel[1]:.1f})  normalized ({loc.normalized[0]:.3f}, {loc.normalized[1]:.3f})")
    if loc.goal is not None:
        x, y, z = loc.goal.point
        print(f"3D goal:  ({x:.2f}, {y:.2f}, {z:.2f}) m in the map frame, {loc.goal.distance:.2f} m from the camera "
              f"({loc.goal.method})")
    else:
        print(f"3D goal:  none ({loc.goal_error})")
    print(f"answer:   {loc.raw_answer!r} ({loc.status}, {loc.latency_s * 1000:.0f} ms, {loc.exchanges} exchange(s))")
    return 0


if __name__ == "__main__":
    sys.exit(main())
