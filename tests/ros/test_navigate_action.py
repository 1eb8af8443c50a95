"""The goal sent as a navigation action, its outcome on ``~/result``: the node against a tiny action
server of our own on a real ROS 2 graph.

nav2_msgs has no PyPI wheel, so the server serves a stand-in type from PyPI,
``test_msgs/action/Fibonacci``, given to the node as its :class:`NavigationInterface`: the goal pose
the node hands over is recorded where the stand-in's goal is built. Its result has no
``error_code``, as Humble's ``NavigateToPose`` result has none; Iron's and later results, which
have one, are read by ``outcome_of`` (the last tests).
"""

from __future__ import annotations

import json
import threading
from types import SimpleNamespace

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")
pytest.importorskip("test_msgs", reason="test_msgs (the stand-in action type) comes with the test extra")


@pytest.fixture
def no_model():
    """A locate function these tests never reach (no command is answered)."""

    def locate(*args):
        raise AssertionError("no command is answered in these tests")

    return locate


GOAL = (1.5, -2.0, 0.0)


@pytest.fixture
def navigation(ros_graph, no_model):
    """A tiny action server answering each goal as ``plan`` says (``succeed``, ``abort`` or
    ``reject``), the node sending its goals there, and the ``~/result`` messages it published."""
    import rclpy
    from rclpy.action import ActionServer, GoalResponse
    from rclpy.parameter import Parameter
    from std_msgs.msg import String
    from test_msgs.action import Fibonacci

    from povagent.ros.navigate_action import NavigationInterface
    from povagent.ros.node import GroundingNode

    plan: list[str] = []
    poses: list = []

    def goal_for(pose):
        poses.append(pose)
        return Fibonacci.Goal(order=len(poses))

    def execute(handle):
        getattr(handle, {"succeed": "succeed", "abort": "abort"}[plan[0]])()
        return Fibonacci.Result(sequence=[0, 1, 1])

    server_node = ros_graph.add(rclpy.create_node("tiny_navigator", context=ros_graph.context))
    server = ActionServer(server_node, Fibonacci, "/tiny/navigate_to_pose", execute,
                          goal_callback=lambda goal: GoalResponse.REJECT if plan[0] == "reject" else GoalResponse.ACCEPT)
    node = ros_graph.add(GroundingNode(no_model, name="navigating", context=ros_graph.context,
                                       parameter_overrides=[Parameter("navigate_action", value="/tiny/navigate_to_pose")],
                                       navigation=NavigationInterface(Fibonacci, goal_for)))
    results: list[dict] = []
    lock = threading.Lock()

    def take(msg):
        with lock:
            results.append(json.loads(msg.data))

    server_node.create_subscription(String, "/navigating/result", take, 10)
    try:
        yield SimpleNamespace(node=node, plan=plan, poses=poses, results=results, server_node=server_node)
    finally:
        for n in (node, server_node):
            ros_graph.remove(n)
        node.close()
        server.destroy()
        server_node.destroy_node()


def answered(command):
    """What the worker publishes for a command whose answer has a goal."""
    from povagent.ros.result import CommandResult

    return CommandResult(command=command, status="ok", goal=GOAL, viewpoint=(0.0, 0.0, 1.0), frame_stamp_ns=5 * 10**9, map_frame="map", keyframes=3)


def navigation_of(results, command):
    return [r["navigation"] for r in results if r["command"] == command]


def ready(nav, wait_until):
    wait_until(lambda: nav.node.navigate.client.server_is_ready() and nav.node.result_pub.get_subscription_count(),
               what="the node to discover the action server")


def test_the_goal_goes_to_the_action_and_its_success_follows_on_result(navigation, wait_until):
    navigation.plan.append("succeed")
    ready(navigation, wait_until)
    navigation.node.publish_result(answered("the mug"))
    outcomes = wait_until(lambda: len(navigation_of(navigation.results, "the mug")) == 2 and navigation_of(navigation.results, "the mug"),
                          what="the answer and the navigation's outcome")
    assert [o["status"] for o in outcomes] == ["sent", "succeeded"]
    assert outcomes[1] == {"action": "/tiny/navigate_to_pose", "status": "succeeded", "reason": "", "error_code": None, "error_msg": ""}
    [pose] = navigation.poses
    assert pose.header.frame_id == "map" and (pose.pose.position.x, pose.pose.position.y, pose.pose.position.z) == GOAL


def test_with_the_action_the_goal_is_not_published_on_goal_pose(navigation):
    published = dict(navigation.node.get_publisher_names_and_types_by_node("navigating", "/"))
    assert "/goal_pose" not in published and "/navigating/goal" in published


@pytest.mark.parametrize(("server", "status"), [("abort", "aborted"), ("reject", "rejected")])
def test_a_navigation_that_fails_says_how_on_result(navigation, wait_until, server, status):
    navigation.plan.append(server)
    ready(navigation, wait_until)
    navigation.node.publish_result(answered(f"the mug ({server})"))
    outcomes = wait_until(lambda: len(navigation_of(navigation.results, f"the mug ({server})")) == 2
                          and navigation_of(navigation.results, f"the mug ({server})"), what="the navigation's outcome")
    assert [o["status"] for o in outcomes] == ["sent", status]


def test_with_no_action_server_up_the_answer_says_unavailable_and_nothing_is_sent(ros_graph, no_model, wait_until):
    from rclpy.parameter import Parameter
    from test_msgs.action import Fibonacci

    from povagent.ros.navigate_action import NavigationInterface
    from povagent.ros.node import GroundingNode
    from povagent.ros.result import NavigationStatus

    sent = []
    node = GroundingNode(no_model, name="navigating_alone", context=ros_graph.context,
                         parameter_overrides=[Parameter("navigate_action", value="/nobody/navigate_to_pose")],
                         navigation=NavigationInterface(Fibonacci, lambda pose: sent.append(pose) or Fibonacci.Goal()))
    try:
        outcome = node.navigate.send(object(), answered("the mug"))
        assert outcome.status == NavigationStatus.UNAVAILABLE and "no /nobody/navigate_to_pose action server is up" in outcome.reason
        assert sent == []
    finally:
        node.close()


def test_without_nav2_msgs_the_option_is_one_config_error_naming_it(ros_graph, no_model):
    import importlib.util

    from rclpy.parameter import Parameter

    from povagent.errors import ConfigError
    from povagent.ros.node import GroundingNode

    if importlib.util.find_spec("nav2_msgs") is not None:
        pytest.skip("Nav2 is installed here: nav2_msgs is found")
    with pytest.raises(ConfigError, match=r"^ros-node parameters: navigate_action needs nav2_msgs .*no PyPI wheel"):
        GroundingNode(no_model, name="navigating_without_nav2", context=ros_graph.context,
                      parameter_overrides=[Parameter("navigate_action", value="navigate_to_pose")])


def test_a_result_with_an_error_code_puts_it_in_the_outcome():
    from action_msgs.msg import GoalStatus

    from povagent.ros.navigate_action import outcome_of

    iron_result = SimpleNamespace(error_code=203, error_msg="no valid path")  # NavigateToPose's result since Iron
    outcome = outcome_of("navigate_to_pose", GoalStatus.STATUS_ABORTED, iron_result)
    assert (outcome.status, outcome.error_code, outcome.error_msg) == ("aborted", 203, "no valid path")


def test_a_humble_result_with_no_error_code_leaves_it_empty():
    from action_msgs.msg import GoalStatus
    from std_msgs.msg import Empty

    from povagent.ros.navigate_action import outcome_of

    humble_result = SimpleNamespace(result=Empty())  # NavigateToPose's result in Humble: std_msgs/Empty result
    outcome = outcome_of("navigate_to_pose", GoalStatus.STATUS_SUCCEEDED, humble_result)
    assert (outcome.status, outcome.error_code, outcome.error_msg) == ("succeeded", None, "")
