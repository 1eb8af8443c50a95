"""The ROS 2 commands: ``ros-node`` (the live node) and ``ros-replay`` (a recorded bag).

Both build a :class:`~povagent.agent.grounding_agent.GroundingAgent` from ``--pipeline`` or
``--model`` with the map's floor (z-up, ``--floor-height``) and hand it to the same session;
:mod:`povagent.ros` is imported only here. Without the ``ros`` (node) or ``bags`` (replay) extra
they stop with one line naming it.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

import typer

from povagent.cli import app
from povagent.cli.options import trust_remote_code_option


def _agent(pipeline: Path | None, model: str | None, floor_height: float, timeout: float | None, trust_remote_code: bool) -> Any:
    from povagent.agent import GroundingAgent
    from povagent.errors import ConfigError
    from povagent.geometry.goals import Plane

    if (pipeline is None) == (model is None):
        raise ConfigError("give --pipeline P.yaml or --model M (one of them)")
    plane = Plane.horizontal(floor_height, up_axis="z")
    extra: dict[str, Any] = {"plane": plane, "trust_remote_code": trust_remote_code}
    if timeout is not None:
        extra["timeout_s"] = timeout
    if pipeline is not None:
        return GroundingAgent.from_pipeline(pipeline, **extra)
    return GroundingAgent(model=model, **extra)


@app.command("ros-node", context_settings={"allow_extra_args": True, "ignore_unknown_options": True})
def ros_node_command(
    ctx: typer.Context,
    pipeline: Path = typer.Option(None, "--pipeline", metavar="P.yaml", help="Pipeline YAML (backend/model, strategy, parser, timeout)."),
    model: str = typer.Option(None, "--model", metavar="M", help="A litellm model string or profile name (basic strategy)."),
    floor_height: float = typer.Option(0.0, "--floor-height", metavar="Z", help="Height of the floor in the map frame (metres; the map is z-up)."),
    timeout: float = typer.Option(None, "--timeout", metavar="S", help="Seconds for one command, retries included (default: the pipeline's)."),
    trust_remote_code: bool = trust_remote_code_option(),
) -> None:
    """Run the grounding agent as a ROS 2 node until Ctrl-C.

    Images, camera_info and transforms in; a command on ~/command; the goal on ~/goal and
    /goal_pose, the answer as JSON on ~/result. ROS arguments follow, e.g.
    --ros-args -p image_topic:=/cam/image -r /goal_pose:=/nav/goal (needs pip install 'povagent[ros]').
    """
    from povagent.errors import ConfigError
    from povagent.ros.extras import discovery_summary, require_rclpy

    rclpy = require_rclpy("ros-node")
    typer.echo(discovery_summary(), err=True)
    agent = _agent(pipeline, model, floor_height, timeout, trust_remote_code)
    from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor

    from povagent.ros.node import GroundingNode
    from povagent.ros.session import agent_locate

    try:
        rclpy.init(args=["povagent", *ctx.args])
    except RuntimeError as exc:  # rclpy's RCLError: ROS arguments rcl cannot read
        agent.close()
        raise ConfigError(_ros_arguments_problem(str(exc))) from None
    node = GroundingNode(agent_locate(agent))
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass  # Ctrl-C or SIGTERM: rclpy's signal handler shut the context down
    finally:
        # the order rclpy requires: the executor, then the node, then the context
        executor.shutdown(timeout_sec=5)
        node.close()
        agent.close()
        rclpy.try_shutdown()


def _ros_arguments_problem(rcl_message: str) -> str:
    """rcl's refusal of the ROS arguments as one line: its source locations dropped, and for an
    array mixing whole numbers and decimals (YAML types them apart) what to write instead."""
    text = re.sub(r"(,? at /\S+:\d+)+|,? at line_num \d+", "", rcl_message).removeprefix("failed to initialize rcl: ").strip()
    hint = ""
    if "Sequence should be of same type" in text:
        hint = ' (write every number of an array as a decimal, 0.0 not 0, or give mount_transform as one string: mount_transform:="x y z qx qy qz qw")'
    return f"ros-node: the ROS arguments could not be read: {text}{hint}"


@app.command("ros-replay")
def ros_replay_command(
    bag: Path = typer.Argument(..., metavar="BAG", help="A ROS 2 bag folder (sqlite3 or mcap storage)."),
    command: str = typer.Option(..., "--command", metavar="TEXT", help="The user's sentence."),
    pipeline: Path = typer.Option(None, "--pipeline", metavar="P.yaml", help="Pipeline YAML (backend/model, strategy, parser, timeout)."),
    model: str = typer.Option(None, "--model", metavar="M", help="A litellm model string or profile name (basic strategy)."),
    image_topic: str = typer.Option("/camera/image_raw", "--image-topic", metavar="TOPIC", help="Image or CompressedImage topic."),
    camera_info_topic: str = typer.Option("/camera/camera_info", "--camera-info-topic", metavar="TOPIC", help="CameraInfo topic."),
    depth_topic: str = typer.Option("/camera/depth/image_raw", "--depth-topic", metavar="TOPIC", help="Depth image topic ('' for none)."),
    odom_topic: str = typer.Option("/odom", "--odom-topic", metavar="TOPIC", help="nav_msgs/Odometry topic ('' for none)."),
    map_frame: str = typer.Option("map", "--map-frame", metavar="FRAME", help="The frame goals are given in."),
    min_translation: float = typer.Option(0.5, "--min-translation", metavar="M", help="Keep a frame after moving this far (metres)."),
    min_rotation: float = typer.Option(30.0, "--min-rotation", metavar="DEG", help="Keep a frame after turning this far (degrees)."),
    max_frames: int = typer.Option(30, "--max-frames", min=1, metavar="N", help="Frames kept at most."),
    floor_height: float = typer.Option(0.0, "--floor-height", metavar="Z", help="Height of the floor in the map frame (metres)."),
    timeout: float = typer.Option(None, "--timeout", metavar="S", help="Seconds for the command, retries included."),
    as_json: bool = typer.Option(False, "--json", help="Print the ~/result JSON instead of a table."),
    save_memory: Path = typer.Option(None, "--save-memory", metavar="DIR", help="Write the keyframe memory (frames, poses, intrinsics) to DIR."),
    trust_remote_code: bool = trust_remote_code_option(),
) -> None:
    """Answer one command over a recorded ROS 2 bag.

    The bag goes through the node's own code path (same keyframes, same goal); needs
    pip install 'povagent[bags]'.
    """
    from povagent.ros.extras import require_rosbags

    require_rosbags("ros-replay")
    from povagent.ros.bag_replay import ReplayTopics, replay_bag
    from povagent.ros.keyframes import MemorySettings
    from povagent.ros.memory_folder import check_memory_folder
    from povagent.ros.memory_folder import save_memory as write_memory
    from povagent.ros.session import GroundingSession, agent_locate

    if save_memory is not None:
        check_memory_folder(save_memory)  # before the bag is read: a folder we may not write is one line at once
    settings = MemorySettings(min_translation, min_rotation, max_frames)
    topics = ReplayTopics(image=image_topic, camera_info=camera_info_topic, depth=depth_topic, odom=odom_topic)
    agent = _agent(pipeline, model, floor_height, timeout, trust_remote_code)
    with agent:
        session = GroundingSession(agent_locate(agent), map_frame=map_frame, settings=settings)
        read = replay_bag(bag, session, topics)
        if save_memory is not None:
            write_memory(session.memory, save_memory)
        result = session.answer(command)
    problems = ", ".join(f"{kind} {n}" for kind, n in sorted(session.problems.items()))
    if problems:
        typer.echo(f"malformed messages: {problems}", err=True)
    if as_json:
        typer.echo(result.model_dump_json())
    else:
        rows = [
            ("bag", f"{bag} ({read} messages, {session.images_seen} images, {result.keyframes} kept)"),
            ("status", f"{result.status}" + (f" ({result.reason})" if result.reason else "")),
        ]
        if result.frame_index is not None:
            rows.append(("keyframe", f"{result.frame_index} at {result.frame_stamp_ns / 1e9:.3f} s in {result.frame_id}"))  # type: ignore[operator]
        if result.pixel is not None:
            rows.append(("pixel", f"({result.pixel[0]:.1f}, {result.pixel[1]:.1f})"))
        if result.goal is not None:
            rows.append(("goal", f"({result.goal[0]:.3f}, {result.goal[1]:.3f}, {result.goal[2]:.3f}) m in {result.map_frame} ({result.goal_method})"))
        if save_memory is not None:
            rows.append(("memory", str(save_memory)))
        for key, value in rows:
            typer.echo(f"{key:<9} {value}")
    if result.status not in ("ok", "no_goal"):
        sys.exit(1)


__all__ = ["ros_node_command", "ros_replay_command"]
