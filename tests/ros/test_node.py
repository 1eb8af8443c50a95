"""The node on a real ROS 2 graph: a player publishes a generated house's tour and a command,
the node answers on ~/result, ~/goal and /goal_pose.

One node serves every test of this module (started once, stopped at the end); each test looks
at the results published after it spoke.
"""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest

from povagent.ros.session import GroundingSession
from povagent.ros.transforms import rotation_from_quaternion

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")

#: Simulated exact perception: the goal is the ground truth within the box fit's error (m),
#: the tolerance examples/robot_app.py is held to.
GOAL_TOLERANCE = 0.05


class Listener:
    """Collects ~/result, ~/goal and /goal_pose messages."""

    def __init__(self, node):
        from geometry_msgs.msg import PointStamped, PoseStamped
        from std_msgs.msg import String

        self.results: list[dict] = []
        self.goals: list = []
        self.poses: list = []
        self.lock = threading.Lock()
        node.create_subscription(String, "/povagent/result", lambda m: self._add(self.results, json.loads(m.data)), 10)
        node.create_subscription(PointStamped, "/povagent/goal", lambda m: self._add(self.goals, m), 10)
        node.create_subscription(PoseStamped, "/goal_pose", lambda m: self._add(self.poses, m), 10)

    def _add(self, into, item):
        with self.lock:
            into.append(item)

    def answers_for(self, command):
        with self.lock:
            return [r for r in self.results if r["command"] == command and r["status"] not in ("queued", "queue_full")]


@pytest.fixture(scope="module")
def live(ros_graph, tour, simulated_locate, wait_until):
    """The povagent node and a player node on the graph, the tour already played."""
    import rclpy
    from rclpy.parameter import Parameter

    from povagent.ros.node import GroundingNode
    from povagent.ros.tour_player import TourPlayer, camera_info, mount_parameters

    params = {**mount_parameters(tour), "odom_topic": "/odom", "reliable_images": True, "max_queue": 2}
    overrides = [Parameter(k, value=v) for k, v in params.items()]
    node = ros_graph.add(GroundingNode(simulated_locate, context=ros_graph.context, parameter_overrides=overrides))
    player_node = ros_graph.add(rclpy.create_node("tour_player", context=ros_graph.context))
    player = TourPlayer(player_node)
    listener = Listener(player_node)
    wait_until(lambda: player.image.get_subscription_count() and player.command.get_subscription_count()
               and node.result_pub.get_subscription_count(), what="the node and the player to discover each other")
    player.info.publish(camera_info(tour, tour.frames[0].stamp_ns))  # as a driver does before its first image
    wait_until(lambda: node.session.calibrated, what="the node to take the camera_info")
    player.play(tour, after_each=lambda i: wait_until(lambda: node.session.images_seen > i, what=f"the node to take image {i}"))
    wait_until(lambda: len(node.session.memory) == len(tour.frames), what="every tour frame in the memory")
    try:
        yield node, player, listener
    finally:
        for n in (node, player_node):
            ros_graph.remove(n)
        node.close()
        player_node.destroy_node()


def test_the_node_publishes_the_goal_the_agent_finds_for_the_same_frames_and_cameras(live, tour, simulated_locate, wait_until):
    _, player, listener = live
    player.say(tour.truth.sentence)
    [result] = wait_until(lambda: listener.answers_for(tour.truth.sentence), timeout=60, what="the node's answer")
    assert result["status"] == "ok", result
    direct = simulated_locate(tour.truth.sentence, [f.rgb for f in tour.frames], tour.cameras(), [None] * len(tour.frames))
    assert np.allclose(result["goal"], direct.goal.point, atol=1e-6, rtol=0)
    assert result["frame_index"] == direct.frame_index and result["frame_stamp_ns"] == tour.frames[direct.frame_index].stamp_ns
    assert np.linalg.norm(np.array(result["goal"]) - np.array(tour.truth.target)) < GOAL_TOLERANCE


def test_the_goal_topics_carry_the_goal_in_the_map_facing_from_the_keyframe(live, tour, wait_until):
    _, player, listener = live
    sentence = tour.truth.sentence + " (topics)"
    player.say(sentence)
    [result] = wait_until(lambda: listener.answers_for(sentence), timeout=60, what="the node's answer")
    point = wait_until(lambda: [g for g in listener.goals if (g.point.x, g.point.y, g.point.z) == tuple(result["goal"])], what="~/goal")[0]
    assert point.header.frame_id == "map"
    pose = wait_until(lambda: [p for p in listener.poses if p.pose.position.x == result["goal"][0]], what="/goal_pose")[0]
    q = pose.pose.orientation
    heading = rotation_from_quaternion((q.x, q.y, q.z, q.w))[:, 0]
    towards = np.array(result["goal"][:2]) - np.array(result["viewpoint"][:2])
    assert np.allclose(heading[:2], towards / np.linalg.norm(towards), atol=1e-9) and heading[2] == pytest.approx(0.0)


def test_malformed_messages_of_each_kind_leave_the_node_alive_and_answering(live, tour, wait_until):
    from povagent.ros.tour_player import camera_info, image, odometry

    node, player, listener = live
    frame = tour.frames[0]
    late = frame.stamp_ns + 10**9 * 1000  # far from every transform
    bad_encoding = image(frame.rgb, frame.stamp_ns)
    bad_encoding.encoding = "yuv422"
    empty = image(frame.rgb, frame.stamp_ns)
    empty.height = empty.width = 0
    empty.data = b""
    nan_info = camera_info(tour, frame.stamp_ns)
    nan_info.k = [float("nan")] * 9
    nan_odom = odometry(frame.stamp_ns + 1, frame.map_from_base)
    nan_odom.pose.pose.position.x = float("nan")
    before = dict(node.session.problems)
    player.image.publish(bad_encoding)
    player.image.publish(empty)
    player.info.publish(nan_info)
    player.odom.publish(nan_odom)
    player.image.publish(image(frame.rgb, late))  # no transform near its stamp
    wait_until(lambda: all(node.session.problems[k] > before.get(k, 0) for k in ("encoding", "size", "camera_info", "transform")),
               what="every malformed message counted")
    player.odom.publish(odometry(late + 10**9, frame.map_from_base))  # newer transforms: the late image is given up
    wait_until(lambda: node.session.problems["missing_transform"] > before.get("missing_transform", 0), what="the missing transform counted")
    sentence = tour.truth.sentence + " (after malformed input)"
    player.say(sentence)
    [result] = wait_until(lambda: listener.answers_for(sentence), timeout=60, what="an answer after malformed input")
    assert result["status"] == "ok" and result["keyframes"] == len(tour.frames)


@pytest.fixture
def held_model(live):
    """The node's model call held until the test releases it (``release()``), so what happens
    while a command is being answered can be looked at without racing the answer."""
    node = live[0]
    gate = threading.Event()
    original = node.session.locate

    def held(*args):
        gate.wait(30)
        return original(*args)

    node.session.locate = held
    try:
        yield gate.set
    finally:
        gate.set()
        node.session.locate = original


def test_bad_parameters_are_one_config_error_naming_them(ros_graph, simulated_locate):
    from rclpy.parameter import Parameter

    from povagent.errors import ConfigError
    from povagent.ros.node import GroundingNode

    bad = [Parameter("mount_transform", value=[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])]
    with pytest.raises(ConfigError, match=r"^ros-node parameters: parameter mount_transform: the rotation quaternion has norm 0"):
        GroundingNode(simulated_locate, name="bad_node", context=ros_graph.context, parameter_overrides=bad)


def test_images_keep_arriving_while_a_command_is_answered(live, tour, held_model, wait_until):
    from povagent.ros.tour_player import image, odometry

    node, player, listener = live
    sentence = tour.truth.sentence + " (held)"
    player.say(sentence)
    wait_until(lambda: node.answering, what="the worker to start answering")
    seen = node.session.images_seen
    frame = tour.frames[-1]
    later = frame.stamp_ns + 10**8
    player.odom.publish(odometry(later, frame.map_from_base))
    player.image.publish(image(frame.rgb, later))
    wait_until(lambda: node.session.images_seen > seen, what="the image taken while the model call is held")
    assert node.answering and not listener.answers_for(sentence)  # still answering
    held_model()
    [result] = wait_until(lambda: listener.answers_for(sentence), timeout=60, what="the held answer")
    assert result["status"] == "ok"


def test_commands_while_one_is_answered_are_queued_up_to_the_bound_then_refused(live, tour, held_model, wait_until):
    node, player, listener = live
    first, second, third, fourth = (f"{tour.truth.sentence} (queue {i})" for i in range(4))
    player.say(first)
    wait_until(lambda: node.answering, what="the worker to start answering")
    for sentence in (second, third, fourth):
        player.say(sentence)
    statuses = lambda s: [r["status"] for r in listener.results if r["command"] == s]  # noqa: E731
    wait_until(lambda: statuses(fourth), what="the fourth command's result")
    assert statuses(fourth) == ["queue_full"]  # max_queue is 2: the second and third wait
    assert [r["queue_position"] for r in listener.results if r["command"] in (second, third) and r["status"] == "queued"] == [1, 2]
    held_model()
    wait_until(lambda: listener.answers_for(second) and listener.answers_for(third), timeout=90, what="the queued answers")
    assert statuses(second)[-1] == statuses(third)[-1] == "ok" and statuses(fourth) == ["queue_full"]


def test_a_bag_of_the_same_messages_replays_to_the_same_goal(live, tour, simulated_locate, tmp_path, wait_until):
    from povagent.ros.bag_replay import replay_bag
    from povagent.ros.tour_bag import write_tour_bag

    _, player, listener = live
    sentence = tour.truth.sentence + " (bag)"
    player.say(sentence)
    [live_result] = wait_until(lambda: listener.answers_for(sentence), timeout=60, what="the node's answer")
    bag = write_tour_bag(tour, tmp_path / "tour", base_source="odom")
    session = GroundingSession(simulated_locate)
    replay_bag(bag, session)
    replayed = session.answer(sentence)
    assert replayed.goal == tuple(live_result["goal"]) and replayed.frame_stamp_ns == live_result["frame_stamp_ns"]
