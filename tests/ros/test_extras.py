"""Without the extras the ROS commands stop with one line naming the extra; rclpy from PyPI gets
the environment a sourced workspace would give."""

from __future__ import annotations

import sys

import pytest

from povagent.errors import ConfigError
from povagent.ros.extras import prepare_ros_environment, require_rclpy, require_rosbags


def test_a_missing_rclpy_names_the_ros_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rclpy", None)
    with pytest.raises(ConfigError, match=r"^ros-node needs ROS 2's Python packages .*pip install 'povagent\[ros\]'$"):
        require_rclpy("ros-node")


def test_a_missing_rosbags_names_the_bags_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(ConfigError, match=r"^ros-replay needs rosbags: pip install 'povagent\[bags\]'$"):
        require_rosbags("ros-replay")


def test_the_middleware_the_extra_installs_is_chosen_unless_one_is_set(monkeypatch):
    monkeypatch.delenv("RMW_IMPLEMENTATION", raising=False)
    prepare_ros_environment()
    import os

    assert os.environ["RMW_IMPLEMENTATION"] == "rmw_fastrtps_cpp"
    monkeypatch.setenv("RMW_IMPLEMENTATION", "rmw_cyclonedds_cpp")
    prepare_ros_environment()
    assert os.environ["RMW_IMPLEMENTATION"] == "rmw_cyclonedds_cpp"


def test_without_a_home_directory_ros_logs_go_to_a_temporary_folder(monkeypatch):
    import os

    monkeypatch.delenv("HOME", raising=False)
    monkeypatch.delenv("ROS_LOG_DIR", raising=False)
    prepare_ros_environment()
    assert os.path.isdir(os.environ["ROS_LOG_DIR"])


DISCOVERY = ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY")


def test_with_no_discovery_variable_set_ros_discovers_on_this_machine_only(monkeypatch):
    import os

    for name in DISCOVERY:
        monkeypatch.delenv(name, raising=False)
    prepare_ros_environment()
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"


@pytest.mark.parametrize(("name", "value"), [("ROS_AUTOMATIC_DISCOVERY_RANGE", "SUBNET"), ("ROS_STATIC_PEERS", "192.168.1.20"), ("ROS_LOCALHOST_ONLY", "0")])
def test_a_discovery_variable_the_user_set_is_kept_and_no_range_is_added(monkeypatch, name, value):
    import os

    for other in DISCOVERY:
        monkeypatch.delenv(other, raising=False)
    monkeypatch.setenv(name, value)
    prepare_ros_environment()
    assert {k: os.environ.get(k) for k in DISCOVERY} == {k: value if k == name else None for k in DISCOVERY}
