"""With the PyPI packages alone (no /tf read) and no ``map_frame`` given, the node's goals are in
the odometry's own frame, decided by the first odometry message, on a real ROS 2 graph."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")


def test_odometry_in_odom_puts_the_goals_in_odom_when_no_map_frame_is_given(ros_graph, tour, simulated_locate, wait_until):
    import rclpy
    from geometry_msgs.msg import PointStamped
    from rclpy.parameter import Parameter
    from std_msgs.msg import String

    from povagent.ros.extras import tf2_messages
    from povagent.ros.node import GroundingNode
    from povagent.ros.tour_player import TourPlayer, camera_info, image, mount_parameters, odometry

    if tf2_messages() is not None:
        pytest.skip("a ROS installation provides tf2_msgs here: the node reads /tf and goals default to map")
    params = {**mount_parameters(tour), "odom_topic": "/odom", "reliable_images": True}
    node = ros_graph.add(GroundingNode(simulated_locate, name="odom_goals", context=ros_graph.context,
                                       parameter_overrides=[Parameter(k, value=v) for k, v in params.items()]))
    player_node = ros_graph.add(rclpy.create_node("odom_player", context=ros_graph.context))
    results: list[dict] = []
    goals: list = []
    try:
        player = TourPlayer(player_node, command_topic="/odom_goals/command")
        player_node.create_subscription(String, "/odom_goals/result", lambda m: results.append(json.loads(m.data)), 10)
        player_node.create_subscription(PointStamped, "/odom_goals/goal", lambda m: goals.append(m), 10)
        wait_until(lambda: player.image.get_subscription_count() and player.command.get_subscription_count()
                   and node.result_pub.get_subscription_count(), what="the node and the player to discover each other")
        assert node.session.map_frame == ""  # undecided until the first odometry
        player.info.publish(camera_info(tour, tour.frames[0].stamp_ns))
        for i, frame in enumerate(tour.frames):
            in_odom = odometry(frame.stamp_ns, frame.map_from_base)
            in_odom.header.frame_id = "odom"
            player.odom.publish(in_odom)
            player.image.publish(image(frame.rgb, frame.stamp_ns))
            wait_until(lambda i=i: node.session.images_seen > i, what=f"the node to take image {i}")
        wait_until(lambda: len(node.session.memory) == len(tour.frames), what="every frame kept")
        player.say(tour.truth.sentence)
        [result] = wait_until(lambda: [r for r in results if r["command"] == tour.truth.sentence], timeout=60, what="the answer")
        assert result["status"] == "ok" and result["map_frame"] == "odom"
        [goal] = wait_until(lambda: list(goals), what="~/goal")
        assert goal.header.frame_id == "odom" and np.allclose([goal.point.x, goal.point.y, goal.point.z], result["goal"])
    finally:
        for n in (node, player_node):
            ros_graph.remove(n)
        node.close()
        player_node.destroy_node()
