"""Play a generated house's tour to the povagent ROS 2 node, launch-free, in one process.

    python examples/ros/play_to_node.py                 # simulated perception: no model needed

A player node publishes the tour (odometry, camera_info, images; /tf too where a ROS install
provides tf2_msgs), then the command on /povagent/command; the povagent node keeps its keyframes
and answers on /povagent/result, /povagent/goal and /goal_pose. The model's part is a SIMULATION
(povagent_plugins' SimulatedScene: the house's records seen through the node's keyframe cameras,
answering the geometric strategy's questions), so the goal can be checked against the ground
truth: it lands within 0.05 m of it. With --pipeline P.yaml a real pipeline answers instead.

Everything stays on this machine: ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST and a ROS_DOMAIN_ID
(default 42) are set before rclpy starts.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path


def wait(condition, timeout: float, what: str) -> None:
    """Poll until ``condition()`` holds; SystemExit naming ``what`` after ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise SystemExit(f"error: timed out waiting for {what}")
        time.sleep(0.01)


def main(argv: list[str] | None = None) -> int:
    """Play the tour, say the command, print the node's result beside the ground truth."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, help="a POVBench-layout dataset (default: generate one house)")
    ap.add_argument("--pipeline", type=Path, help="a pipeline YAML answering instead of the simulation")
    ap.add_argument("--domain-id", type=int, default=42, help="ROS_DOMAIN_ID of the graph (0-101)")
    args = ap.parse_args(argv)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_DOMAIN_ID"] = str(args.domain_id)

    import numpy as np

    from povagent.agent import GroundingAgent
    from povagent.dataset.loader import load_dataset
    from povagent.geometry.goals import Plane
    from povagent.ros.house_tour import house_tour, well_seen_instance
    from povagent.ros.session import agent_locate

    floor = Plane.horizontal(0.0, up_axis="z")
    with tempfile.TemporaryDirectory(prefix="ros_play_") as scratch:
        dataset = args.dataset
        if dataset is None:
            from povagent.generate import generate_dataset

            dataset = Path(scratch) / "POVBench"
            generate_dataset(dataset, houses=1, seed=0, frames=12, jobs=1, progress=False)
        found = well_seen_instance(load_dataset(dataset))
        if found is None:
            print(f"error: no well-seen Inferred instance in {dataset}", file=sys.stderr)
            return 1
        tour = house_tour(*found)
    truth = tour.truth

    if args.pipeline:
        agent = GroundingAgent.from_pipeline(args.pipeline, plane=floor)
        locate = agent_locate(agent)
    else:
        from povagent_plugins.backends.simulated import SimulatedScene

        agent = None

        def locate(sentence, frames, cameras, depths):
            scene = SimulatedScene(truth.objects, cameras, anchor=truth.anchor, observer=truth.observer, direction=truth.direction, surface=truth.surface)
            with GroundingAgent(backend=scene, strategy="geometric", parser="json", plane=floor) as simulated:
                return simulated.locate(sentence, list(frames), cameras=list(cameras))

    import rclpy
    from rclpy.executors import MultiThreadedExecutor
    from rclpy.parameter import Parameter
    from std_msgs.msg import String

    from povagent.ros.node import GroundingNode
    from povagent.ros.spinning import BackgroundSpin
    from povagent.ros.tour_player import TourPlayer, camera_info, mount_parameters

    rclpy.init()
    params = {**mount_parameters(tour), "odom_topic": "/odom", "reliable_images": True}
    node = GroundingNode(locate, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])
    player_node = rclpy.create_node("tour_player")
    player = TourPlayer(player_node)
    results: list[dict] = []
    player_node.create_subscription(String, "/povagent/result", lambda m: results.append(json.loads(m.data)), 10)
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    executor.add_node(player_node)
    # Shut down in the order rclpy requires: the executor (its thread stopped and joined), then
    # the nodes, then the context; a thread left inside rclpy at exit aborts the process.
    try:
        with BackgroundSpin(executor):
            wait(lambda: player.image.get_subscription_count() and node.result_pub.get_subscription_count(), 20, "discovery")
            player.info.publish(camera_info(tour, tour.frames[0].stamp_ns))
            wait(lambda: node.session.calibrated, 20, "the camera_info")
            player.play(tour, after_each=lambda i: wait(lambda: node.session.images_seen > i, 20, f"image {i}"))
            wait(lambda: len(node.session.memory) == len(tour.frames), 20, "the keyframes")
            player.say(truth.sentence)
            wait(lambda: any(r["status"] not in ("queued",) for r in results), 120, "the node's answer")
    finally:
        node.close()
        player_node.destroy_node()
        if agent is not None:
            agent.close()
        rclpy.shutdown()
    result = results[-1]
    if not args.pipeline:
        print("perception: SIMULATION (the house's records seen through the keyframe cameras; not a model)")
    print(f"command:   {truth.sentence}")
    print(f"keyframes: {result['keyframes']} kept of {len(tour.frames)} images")
    print(f"status:    {result['status']} {result['reason']}".rstrip())
    if result["goal"] is not None:
        goal = np.array(result["goal"])
        print(f"goal:      ({goal[0]:.3f}, {goal[1]:.3f}, {goal[2]:.3f}) m in map, from keyframe {result['frame_index']}")
        print(f"truth:     ({truth.target[0]:.3f}, {truth.target[1]:.3f}, {truth.target[2]:.3f}) m in map")
        print(f"error:     {float(np.linalg.norm(goal - np.array(truth.target))):.3f} m")
    return 0 if result["status"] in ("ok", "no_goal") else 1


if __name__ == "__main__":
    sys.exit(main())
