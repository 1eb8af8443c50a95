"""A robot app embedding povagent's GroundingAgent: frames + a user's sentence -> a 3D goal.

Runs offline as is: the ``geometric`` solver end to end on a house generated on the spot, with
the model's part (reading the sentence, pointing at furniture) SIMULATED from the house's
records, so the goal can be checked against the benchmark's ground truth::

    python examples/robot_app.py                          # generate one house, simulated perception
    python examples/robot_app.py --dataset DIR [--instance HOUSE/PAIR/DIRECTION/a]

With a real model the same frames and cameras go to it instead (no simulation)::

    python examples/robot_app.py --pipeline my_pipeline.yaml     # strategy: geometric in it
    OPENAI_API_KEY=... python examples/robot_app.py --model openai/gpt-5.4

The robot here is a ROS-style one: its world is a z-up, right-handed ``map`` with the floor at
z = 0; its camera poses are 4x4 camera-to-map matrices in the OpenCV optical convention (x right,
y down, z forward); its frames are 640x480 with a calibration matrix K. A generated house is
AI2-THOR's world (y up, left-handed) with 512x512 frames, so the example first turns it into that
robot's view of it (``robot_view``): a real robot has its own poses, K and frames already, and
starts at ``locate``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from PIL import Image

from povagent.agent import GroundingAgent
from povagent.errors import BadInputError, GroundingError, NoAnswerError, PovagentError, UnparseableAnswerError
from povagent.geometry.goals import PinholeCamera, Plane

#: The robot's frames: the house's 512x512 frames resized to 640x640, 80 rows cut top and bottom.
WIDTH, HEIGHT = 640, 480
#: AI2-THOR's axes (x right, y up, z forward) in the robot's map (x forward, y left, z up).
THOR_TO_MAP = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
#: The robot's floor: the map's z = 0 (the plane's normal is the world's up).
FLOOR = Plane.horizontal(0.0, up_axis="z")


@dataclass
class RobotView:
    """What a robot has: 640x480 RGB frames and, for each, its camera (pose in the map, K)."""

    frames: list[Image.Image]
    cameras: list[PinholeCamera]


def robot_view(instance) -> RobotView:
    """The generated house as the ROS robot would have recorded it (see the module docstring)."""
    frames, cameras = [], []
    for frame in instance.frames:
        thor = frame.camera
        scale = WIDTH / thor.width
        top = (WIDTH - HEIGHT) // 2
        with Image.open(frame.file) as im:
            frames.append(im.convert("RGB").resize((WIDTH, WIDTH), Image.Resampling.BICUBIC).crop((0, top, WIDTH, top + HEIGHT)))
        fx, fy, cx, cy = thor.intrinsics
        k = [[fx * scale, 0.0, cx * scale], [0.0, fy * scale, cy * scale - top], [0.0, 0.0, 1.0]]
        in_thor = PinholeCamera.from_camera(thor, "opencv").camera_to_world
        pose = np.eye(4)  # camera-to-map, OpenCV optical axes
        pose[:3, :3] = THOR_TO_MAP @ in_thor[:3, :3]
        pose[:3, 3] = THOR_TO_MAP @ in_thor[:3, 3]
        cameras.append(PinholeCamera.from_intrinsics(pose, k, WIDTH, HEIGHT, convention="opencv"))
    return RobotView(frames, cameras)


def simulated_perception(instance, cameras: list[PinholeCamera]):
    """A SIMULATION of the model's part, answered from the house's records: which furniture the
    speaker used, the anchor, the direction, the surface, and where each object shows in each
    frame (its 3D box seen through the robot's cameras). Not a model."""
    from povagent.dataset.loader import load_house
    from povagent.geometry.placement import surface_kind
    from povagent_plugins.backends.simulated import SimulatedScene

    folder = Path(instance.frames[0].file).parent
    while not (folder / f"{instance.house_id}.json").is_file():
        folder = folder.parent
    house = load_house(folder, folder.parent.parent, [])
    pair = house.pairs[instance.pair_id]
    objects = {}
    for obj in (instance.anchor_object, instance.observer_object):
        corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float) @ THOR_TO_MAP.T
        objects[obj.object_type] = (corners.min(axis=0), corners.max(axis=0))
    return SimulatedScene(
        objects,
        cameras,
        observer=instance.observer_object.object_type,
        anchor=instance.anchor_object.object_type,
        direction=str(instance.direction),
        surface=surface_kind(pair.stage3[instance.direction].surface, pair.landmark_type),
    )


def pick_instance(dataset, wanted: str | None):
    """``wanted`` (an instance id), else the first Inferred command whose anchor and the
    speaker's furniture (of different types) each show in two or more frames."""
    for instance in dataset.instances(conditions=["a"]):
        if wanted is not None:
            if instance.id == wanted:
                return instance
            continue
        house = dataset.houses[instance.house_id]
        objects = (instance.anchor_object, instance.observer_object)
        seen = [sum(o.objectId in r.object_in_frame_hits for r in house.exploration) for o in objects]
        if min(seen) >= 2 and objects[0].object_type != objects[1].object_type:
            return instance
    return None


def main(argv: list[str] | None = None) -> int:
    """Locate one command in a house's frames and print the frame, the pixel and the 3D goal."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", help="a POVBench-layout dataset (default: generate one house in a temporary folder)")
    ap.add_argument("--instance", help="the Inferred instance to run, HOUSE/PAIR/DIRECTION/a (default: the first well-seen one)")
    ap.add_argument("--pipeline", help="pipeline YAML with a real model (backend/model, strategy, parser, timeout)")
    ap.add_argument("--model", help="a litellm model string or profile name, e.g. openai/gpt-5.4 (strategy geometric)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds for the whole call, retries included")
    args = ap.parse_args(argv)

    from povagent.dataset.loader import load_dataset

    with tempfile.TemporaryDirectory(prefix="robot_app_") as scratch:
        try:
            if args.dataset:
                root = Path(args.dataset)
            else:
                from povagent.generate import generate_dataset

                root = Path(scratch) / "POVBench"
                generate_dataset(root, houses=1, seed=0, frames=12, jobs=1, progress=False)
            dataset = load_dataset(root)
        except PovagentError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        instance = pick_instance(dataset, args.instance)
        if instance is None:
            print(f"error: no {'instance ' + args.instance if args.instance else 'well-seen Inferred instance'} in {root}", file=sys.stderr)
            return 1
        robot = robot_view(instance)  # a real robot: its own frames, poses and K
        simulated = not (args.pipeline or args.model)
        try:
            if args.pipeline:
                agent = GroundingAgent.from_pipeline(args.pipeline, plane=FLOOR, timeout_s=args.timeout)
            elif args.model:
                agent = GroundingAgent(model=args.model, strategy="geometric", plane=FLOOR, timeout_s=args.timeout)
            else:
                backend = simulated_perception(instance, robot.cameras)
                agent = GroundingAgent(backend=backend, strategy="geometric", parser="json", plane=FLOOR, timeout_s=args.timeout)
        except PovagentError as exc:  # a bad pipeline file, an unknown plugin name, a missing option
            print(f"error: {exc}", file=sys.stderr)
            return 1

        with agent:
            try:
                loc = agent.locate(instance.sentence, robot.frames, cameras=robot.cameras)
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

    if simulated:
        print("perception: SIMULATION (the simulated scene answers the solver's questions from the house's records; not a model)")
    print(f"sentence: {instance.sentence}")
    print(f"frame:    {loc.frame_index} of {len(robot.frames)} ({loc.frame_size[0]}x{loc.frame_size[1]})")
    print(f"pixel:    ({loc.pixel[0]:.1f}, {loc.pixel[1]:.1f})  normalized ({loc.normalized[0]:.3f}, {loc.normalized[1]:.3f})")
    if loc.goal is not None:
        x, y, z = loc.goal.point
        print(f"3D goal:  ({x:.3f}, {y:.3f}, {z:.3f}) m in the map frame, {loc.goal.distance:.2f} m from the camera ({loc.goal.method})")
    else:
        print(f"3D goal:  none ({loc.goal_error})")
    truth = THOR_TO_MAP @ np.asarray(instance.target, dtype=float)
    print(f"truth:    ({truth[0]:.3f}, {truth[1]:.3f}, {truth[2]:.3f}) m in the map frame (the benchmark's ground truth)")
    if loc.goal is not None:
        print(f"error:    {float(np.linalg.norm(np.asarray(loc.goal.point) - truth)):.3f} m")
    print(f"answer:   {loc.exchanges} exchange(s), {loc.latency_s * 1000:.0f} ms; the solver's account (in the benchmark's y-up world):")
    account = loc.raw_answer.split("\n", 1)[1] if "\n" in loc.raw_answer else loc.raw_answer
    print("\n".join(f"    {line}" for line in account.splitlines()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
