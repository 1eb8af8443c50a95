"""The node's parameters as ROS arguments carry them: ``mount_transform`` as the docs write it (a
string) or as an array, and one line for a parameter the node cannot use."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed (pip install 'povagent[ros]')")


@pytest.fixture
def no_model():
    """A locate function these tests never reach (no command is answered)."""

    def locate(*args):
        raise AssertionError("no command is answered in these tests")

    return locate

MOUNT = "0.1 0 0.9 -0.5 0.5 -0.5 0.5"


def start_node(ros_graph, locate, name, **params):
    from rclpy.parameter import Parameter

    from povagent.ros.node import GroundingNode

    overrides = [Parameter(k, value=v) for k, v in params.items()]
    return GroundingNode(locate, name=name, context=ros_graph.context, parameter_overrides=overrides)


def test_mount_transform_written_as_the_docs_show_it_is_the_camera_mount(ros_graph, no_model):
    from povagent.ros.camera_mount import mount_from_parameter

    node = start_node(ros_graph, no_model, "mount_string", mount_child="cam_optical_frame", mount_transform=MOUNT)
    try:
        assert np.allclose(node.session.transforms.lookup("base_link", "cam_optical_frame", 0), mount_from_parameter(MOUNT).matrix())
    finally:
        node.close()


def test_mount_transform_as_an_array_of_whole_numbers_is_taken(ros_graph, no_model):
    node = start_node(ros_graph, no_model, "mount_ints", mount_child="cam_optical_frame", mount_transform=[0, 0, 1, 0, 0, 0, 1])
    try:
        assert np.allclose(node.session.transforms.lookup("base_link", "cam_optical_frame", 0)[:3, 3], [0.0, 0.0, 1.0])
    finally:
        node.close()


def test_mount_transform_of_another_shape_is_one_config_error_saying_what_is_expected(ros_graph, no_model):
    from povagent.errors import ConfigError

    with pytest.raises(
        ConfigError, match=r'^ros-node parameters: parameter mount_transform: expected seven numbers "x y z qx qy qz qw" \(a string or an array\), got 6 number'
    ):
        start_node(ros_graph, no_model, "mount_six", mount_transform="0 0 0 0 0 1")


def test_a_parameter_of_the_wrong_type_is_one_config_error_naming_it(ros_graph, no_model):
    from povagent.errors import ConfigError

    with pytest.raises(ConfigError, match=r"^ros-node parameters: parameter max_frames must be of the type of its default, 30$"):
        start_node(ros_graph, no_model, "frames_word", max_frames="many")
