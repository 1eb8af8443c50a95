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

One thing is set for safety: ROS 2 itself discovers and is discovered on the whole local network
(``SUBNET``, multicast on every interface), so anyone on the LAN could send the node commands,
fake its sensor data and read its goals. When the user has set none of the discovery variables
(:data:`DISCOVERY_VARIABLES`), ``ROS_AUTOMATIC_DISCOVERY_RANGE`` is set to ``LOCALHOST``: only
processes on this machine meet. A value the user set, any of the three, is kept as it is;
:func:`discovery_summary` is the line ``ros-node`` prints at start.

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
#: The variables by which a user chooses who the node meets; with none set, povagent's default applies.
DISCOVERY_VARIABLES = ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_STATIC_PEERS", "ROS_LOCALHOST_ONLY")
#: povagent's discovery range when the user has chosen none: this machine only.
DEFAULT_DISCOVERY_RANGE = "LOCALHOST"


def prepare_ros_environment() -> None:
    """Set what rclpy from PyPI needs and a sourced workspace would have set (see the module docstring)."""
    os.environ.setdefault("RMW_IMPLEMENTATION", DEFAULT_RMW)
    if not any(os.environ.get(name) for name in DISCOVERY_VARIABLES):
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = DEFAULT_DISCOVERY_RANGE
    if not os.environ.get("HOME") and not os.environ.get("ROS_LOG_DIR"):
        folder = os.path.join(tempfile.gettempdir(), "povagent-ros-log")
        os.makedirs(folder, exist_ok=True)
        os.environ["ROS_LOG_DIR"] = folder


def discovery_range() -> str:
    """The discovery range ROS 2 uses with this environment (``LOCALHOST``, ``SUBNET``, ``OFF``,
    ``SYSTEM_DEFAULT``): ``ROS_LOCALHOST_ONLY=1`` (deprecated) wins, an unset range is ``SUBNET``."""
    if os.environ.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
        return "LOCALHOST"
    return os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper() or "SUBNET"


def discovery_summary() -> str:
    """One line saying who can reach the node: the range, the domain, static peers, the way to change it."""
    reach = discovery_range()
    peers = os.environ.get("ROS_STATIC_PEERS", "").strip()
    line = f"ROS 2 discovery: {reach}, domain {os.environ.get('ROS_DOMAIN_ID', '').strip() or '0'}"
    if peers:
        line += f", static peers {peers}"
    if reach == "LOCALHOST":
        return line + " (this machine only; ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET opens it to the local network)"
    if reach == "SUBNET":
        return line + " (any machine on the local network can command the node and read its goals; secure it with SROS2)"
    return line


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


__all__ = [
    "BAGS_EXTRA", "DEFAULT_DISCOVERY_RANGE", "DEFAULT_RMW", "DISCOVERY_VARIABLES", "ROS_EXTRA", "discovery_range", "discovery_summary",
    "prepare_ros_environment", "require_rclpy", "require_rosbags", "tf2_messages",
]
