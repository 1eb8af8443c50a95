"""The ``ros`` and ``bags`` extras: one line naming the missing one, and the environment rclpy needs.

``povagent[ros]`` installs ROS 2's Python client and message packages from PyPI (``ros-rclpy``
and friends, with the Fast DDS middleware ``ros-rmw-fastrtps-cpp``); ``povagent[bags]`` installs
``rosbags`` (pure Python, no rclpy). The wheels need no sourced ROS workspace: their libraries
are found next to the modules. Two things a sourced workspace would set are set here when
missing, before rclpy is imported:

* ``RMW_IMPLEMENTATION``: ``rmw_fastrtps_cpp``, the middleware the extra installs (a value the
  user set is kept: a robot with Cyclone DDS keeps it);
* ``ROS_LOG_DIR``: rcl writes its log files under ``$HOME/.ros/log`` and refuses to start
  without a home directory (a service account, a bare container); then a temporary folder.

``tf2_msgs`` has no PyPI wheel: where a ROS installation provides it the node subscribes to
``/tf`` and ``/tf_static``; with the PyPI packages alone it takes poses from ``nav_msgs/Odometry``
and a camera mount given as parameters (:func:`tf2_messages`).
"""

from __future__ import annotations

import importlib
import os
import tempfile
from types import ModuleType

from povagent.errors import ConfigError

ROS_EXTRA = "pip install 'povagent[ros]'"
BAGS_EXTRA = "pip install 'povagent[bags]'"
DEFAULT_RMW = "rmw_fastrtps_cpp"


def prepare_ros_environment() -> None:
    """Set what rclpy from PyPI needs and a sourced workspace would have set (see the module docstring)."""
    os.environ.setdefault("RMW_IMPLEMENTATION", DEFAULT_RMW)
    if not os.environ.get("HOME") and not os.environ.get("ROS_LOG_DIR"):
        folder = os.path.join(tempfile.gettempdir(), "povagent-ros-log")
        os.makedirs(folder, exist_ok=True)
        os.environ["ROS_LOG_DIR"] = folder


def require_rclpy(command: str) -> ModuleType:
    """rclpy, imported after :func:`prepare_ros_environment`; :class:`ConfigError` naming the extra when missing."""
    prepare_ros_environment()
    try:
        rclpy = importlib.import_module("rclpy")
        for name in ("std_msgs.msg", "sensor_msgs.msg", "geometry_msgs.msg", "nav_msgs.msg"):
            importlib.import_module(name)
        return rclpy
    except ImportError as exc:
        raise ConfigError(f"{command} needs ROS 2's Python packages ({exc.name or exc} is missing): {ROS_EXTRA}") from None


def require_rosbags(command: str) -> ModuleType:
    """rosbags' high-level reader; :class:`ConfigError` naming the extra when missing."""
    try:
        return importlib.import_module("rosbags.highlevel")
    except ImportError:
        raise ConfigError(f"{command} needs rosbags: {BAGS_EXTRA}") from None


def tf2_messages() -> ModuleType | None:
    """``tf2_msgs.msg`` when a ROS installation provides it, else ``None`` (no PyPI wheel exists)."""
    try:
        return importlib.import_module("tf2_msgs.msg")
    except ImportError:
        return None


__all__ = ["BAGS_EXTRA", "DEFAULT_RMW", "ROS_EXTRA", "prepare_ros_environment", "require_rclpy", "require_rosbags", "tf2_messages"]
