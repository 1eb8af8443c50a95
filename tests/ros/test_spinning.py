"""BackgroundSpin: the executor's thread is stopped and joined before anything is destroyed."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")

from povagent.ros.spinning import SLICE_S, BackgroundSpin


def test_leaving_the_block_joins_the_spinning_thread_before_the_executor_shuts_down(ros_graph, wait_until):
    import rclpy
    from rclpy.executors import MultiThreadedExecutor
    from std_msgs.msg import String

    node = rclpy.create_node("spin_probe", context=ros_graph.context)
    heard: list[str] = []
    node.create_subscription(String, "spin_probe_topic", lambda m: heard.append(m.data), 10)
    talker = node.create_publisher(String, "spin_probe_topic", 10)
    executor = MultiThreadedExecutor(num_threads=2, context=ros_graph.context)
    executor.add_node(node)
    try:
        with BackgroundSpin(executor) as spin:
            wait_until(lambda: talker.get_subscription_count() > 0, what="the probe's own subscription")
            talker.publish(String(data="hello"))
            wait_until(lambda: heard == ["hello"], what="the message spun to its callback")
            started = time.monotonic()
        assert not spin.spinning  # joined, not merely asked to stop
        assert time.monotonic() - started < 1.0 + 10 * SLICE_S
        assert executor.get_nodes() == []  # shut down: rclpy drops the executor's nodes
    finally:
        node.destroy_node()


def test_an_error_raised_while_spinning_reaches_the_caller_on_stop(ros_graph):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node = rclpy.create_node("spin_fault", context=ros_graph.context)

    def fault() -> None:
        raise ValueError("a callback failed")

    node.create_timer(0.01, fault)
    executor = SingleThreadedExecutor(context=ros_graph.context)
    executor.add_node(node)
    spin = BackgroundSpin(executor).start()
    deadline = time.monotonic() + 10
    while spin.spinning and time.monotonic() < deadline:
        time.sleep(0.01)
    try:
        with pytest.raises(ValueError, match="a callback failed"):
            spin.stop()
    finally:
        node.destroy_node()


def test_settle_returns_only_after_a_slice_begun_after_the_call_has_run(ros_graph):
    # what lets the ROS tests destroy a node they took out of the shared executor: no wait set
    # the loop builds after settle() holds it (one built while the node was being destroyed
    # raised InvalidHandle and ended the loop for every later test)
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    node = rclpy.create_node("settle_probe", context=ros_graph.context)
    ran: list[float] = []
    node.create_timer(0.005, lambda: ran.append(time.monotonic()))
    executor = SingleThreadedExecutor(context=ros_graph.context)
    executor.add_node(node)
    try:
        with BackgroundSpin(executor) as spin:
            for _ in range(20):
                called = time.monotonic()
                spin.settle()
                assert any(t > called for t in ran), "settle() returned before a later slice ran"
    finally:
        node.destroy_node()


def test_settle_returns_once_a_later_slice_has_ended(ros_graph):
    from rclpy.executors import SingleThreadedExecutor

    executor = SingleThreadedExecutor(context=ros_graph.context)
    with BackgroundSpin(executor) as spin:
        started = time.monotonic()
        spin.settle()
        assert time.monotonic() - started < 10 * SLICE_S + 1.0
    spin.settle(timeout_s=1.0)  # a loop that has ended: returns at once
