"""The node hears both kinds of camera publisher at its defaults, on a real ROS 2 graph: a driver
publishing best-effort sensor data, and a script publishing once (reliable images, a latched
calibration published before the node started); an image delivered by both subscriptions counts once."""

from __future__ import annotations

import threading

import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")


@pytest.fixture
def graph_node(ros_graph, tour, simulated_locate):
    """``start(prefix)``: the povagent node reading ``<prefix>/image``, ``<prefix>/camera_info`` and
    ``<prefix>/odom`` at the default QoS; ``player``: a node to publish from."""
    import rclpy
    from rclpy.parameter import Parameter

    from povagent.ros.node import GroundingNode
    from povagent.ros.tour_player import mount_parameters

    player = ros_graph.add(rclpy.create_node("camera_publisher", context=ros_graph.context))
    started = []

    def start(prefix):
        params = {**mount_parameters(tour), "image_topic": f"{prefix}/image", "camera_info_topic": f"{prefix}/camera_info",
                  "depth_topic": "", "odom_topic": f"{prefix}/odom"}
        node = GroundingNode(simulated_locate, name=prefix.strip("/") + "_node", context=ros_graph.context,
                             parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])
        started.append(ros_graph.add(node))
        return node

    try:
        yield start, player
    finally:
        for node in started:
            ros_graph.remove(node)
            node.close()
        ros_graph.remove(player)
        player.destroy_node()


def test_a_camera_driver_publishing_best_effort_sensor_data_is_heard(graph_node, tour, wait_until):
    from nav_msgs.msg import Odometry
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import CameraInfo, Image

    from povagent.ros.tour_player import camera_info, image, odometry

    start, player = graph_node
    node = start("/driver")
    images = player.create_publisher(Image, "/driver/image", qos_profile_sensor_data)
    infos = player.create_publisher(CameraInfo, "/driver/camera_info", qos_profile_sensor_data)
    odom = player.create_publisher(Odometry, "/driver/odom", 50)  # the base's odometry: reliable, as a controller publishes it
    wait_until(lambda: images.get_subscription_count() and infos.get_subscription_count() and odom.get_subscription_count(),
               what="the node's subscriptions to match the driver's best-effort publishers")
    for i, frame in enumerate(tour.frames):
        # a driver publishes all the time: the same frame again until the node has it
        def taken(i=i, frame=frame):
            odom.publish(odometry(frame.stamp_ns, frame.map_from_base))
            infos.publish(camera_info(tour, frame.stamp_ns))
            images.publish(image(frame.rgb, frame.stamp_ns))
            return len(node.session.memory) > i
        wait_until(taken, what=f"the node to keep the driver's frame {i}")
    assert len(node.session.memory) == len(tour.frames)


def test_a_script_publishing_once_is_heard_its_calibration_latched_before_the_node_started(graph_node, tour, wait_until):
    from nav_msgs.msg import Odometry
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import CameraInfo, Image

    from povagent.ros.tour_player import camera_info, image, odometry

    start, player = graph_node
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    infos = player.create_publisher(CameraInfo, "/script/camera_info", latched)
    infos.publish(camera_info(tour, tour.frames[0].stamp_ns))  # once, before the node exists
    node = start("/script")
    reliable = QoSProfile(depth=30, reliability=ReliabilityPolicy.RELIABLE)
    images = player.create_publisher(Image, "/script/image", reliable)
    odom = player.create_publisher(Odometry, "/script/odom", reliable)
    wait_until(lambda: node.session.calibrated, what="the latched camera_info to reach the node started after it")
    wait_until(lambda: images.get_subscription_count() == 2 and odom.get_subscription_count(), what="both image subscriptions to match")
    for frame in tour.frames:  # once each, as fast as the script can
        odom.publish(odometry(frame.stamp_ns, frame.map_from_base))
        images.publish(image(frame.rgb, frame.stamp_ns))
    wait_until(lambda: len(node.session.memory) == len(tour.frames), what="every frame the script published once kept")


def test_an_image_delivered_by_both_subscriptions_is_taken_once(graph_node, tour, wait_until):
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import CameraInfo, Image

    from povagent.ros.tour_player import camera_info, image

    start, player = graph_node
    node = start("/twice")
    reliable = QoSProfile(depth=30, reliability=ReliabilityPolicy.RELIABLE)
    images = player.create_publisher(Image, "/twice/image", reliable)
    infos = player.create_publisher(CameraInfo, "/twice/camera_info", reliable)
    wait_until(lambda: images.get_subscription_count() == 2 and infos.get_subscription_count(), what="both image subscriptions to match")
    infos.publish(camera_info(tour, tour.frames[0].stamp_ns))
    frame = tour.frames[0]
    images.publish(image(frame.rgb, frame.stamp_ns))
    wait_until(lambda: node.session.images_seen, what="the image")
    threading.Event().wait(0.5)  # time for the second copy to arrive, were it let through
    assert node.session.images_seen == 1
