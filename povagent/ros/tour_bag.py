"""A house tour written as a ROS 2 bag (with rosbags): what a robot driving the tour would record.

Topics: ``/camera/image_raw`` (``rgb8``), ``/camera/camera_info`` (one per image, ``D`` empty),
the base's pose in the map as ``/tf`` (``map`` -> ``base_link``) or, with ``base_source="odom"``,
as ``/odom`` (``nav_msgs/Odometry``, the same numbers), and the camera mount once on
``/tf_static`` (``base_link`` -> ``camera_color_optical_frame``). Each frame's transform is
written just before its image, at the image's stamp; the bag's log time is the stamp. Storage:
``sqlite3`` (rosbag2's default) or ``mcap``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Literal

import numpy as np

from povagent.ros.extras import require_rosbags
from povagent.ros.house_tour import BASE_FRAME, CAMERA_FRAME, MAP_FRAME, HouseTour
from povagent.ros.transforms import RigidTransform

IMAGE_TOPIC = "/camera/image_raw"
CAMERA_INFO_TOPIC = "/camera/camera_info"


def _time(types: Any, stamp: int) -> Any:
    return types["builtin_interfaces/msg/Time"](sec=stamp // 1_000_000_000, nanosec=stamp % 1_000_000_000)


def _header(types: Any, stamp: int, frame: str) -> Any:
    return types["std_msgs/msg/Header"](stamp=_time(types, stamp), frame_id=frame)


def _transform_stamped(types: Any, stamp: int, parent: str, child: str, t: RigidTransform) -> Any:
    g = "geometry_msgs/msg/"
    return types[g + "TransformStamped"](
        header=_header(types, stamp, parent),
        child_frame_id=child,
        transform=types[g + "Transform"](
            translation=types[g + "Vector3"](x=t.translation[0], y=t.translation[1], z=t.translation[2]),
            rotation=types[g + "Quaternion"](x=t.rotation[0], y=t.rotation[1], z=t.rotation[2], w=t.rotation[3]),
        ),
    )


def _odometry(types: Any, stamp: int, t: RigidTransform) -> Any:
    g = "geometry_msgs/msg/"
    pose = types[g + "Pose"](
        position=types[g + "Point"](x=t.translation[0], y=t.translation[1], z=t.translation[2]),
        orientation=types[g + "Quaternion"](x=t.rotation[0], y=t.rotation[1], z=t.rotation[2], w=t.rotation[3]),
    )
    zero = types[g + "Vector3"](x=0.0, y=0.0, z=0.0)
    return types["nav_msgs/msg/Odometry"](
        header=_header(types, stamp, MAP_FRAME),
        child_frame_id=BASE_FRAME,
        pose=types[g + "PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=types[g + "TwistWithCovariance"](twist=types[g + "Twist"](linear=zero, angular=zero), covariance=np.zeros(36)),
    )


def _camera_info(types: Any, tour: HouseTour, stamp: int) -> Any:
    i = tour.intrinsics
    k = np.array(i.k_matrix())
    p = np.array([k[0], 0.0, k[2], 0.0, 0.0, k[4], k[5], 0.0, 0.0, 0.0, 1.0, 0.0])
    return types["sensor_msgs/msg/CameraInfo"](
        header=_header(types, stamp, CAMERA_FRAME), height=i.height, width=i.width, distortion_model="plumb_bob",
        d=np.zeros(0), k=k, r=np.eye(3).ravel(), p=p, binning_x=0, binning_y=0,
        roi=types["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )


def _image(types: Any, rgb: np.ndarray, stamp: int) -> Any:
    h, w = rgb.shape[:2]
    return types["sensor_msgs/msg/Image"](
        header=_header(types, stamp, CAMERA_FRAME), height=h, width=w, encoding="rgb8", is_bigendian=0, step=w * 3,
        data=np.ascontiguousarray(rgb, dtype=np.uint8).ravel(),
    )


def write_tour_bag(
    tour: HouseTour,
    bag: str | os.PathLike,
    *,
    storage: Literal["sqlite3", "mcap"] = "sqlite3",
    base_source: Literal["tf", "odom"] = "tf",
) -> Path:
    """Write ``tour`` to a new bag folder ``bag`` (see the module docstring); returns its path."""
    require_rosbags("writing a bag")
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    path = Path(bag)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        tf = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=store)
        tf_static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=store)
        odom = writer.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=store)
        image = writer.add_connection(IMAGE_TOPIC, "sensor_msgs/msg/Image", typestore=store)
        info = writer.add_connection(CAMERA_INFO_TOPIC, "sensor_msgs/msg/CameraInfo", typestore=store)

        def write(connection: Any, msg: Any, stamp: int) -> None:
            writer.write(connection, stamp, store.serialize_cdr(msg, connection.msgtype))

        first = tour.frames[0].stamp_ns
        mount = types["tf2_msgs/msg/TFMessage"](transforms=[_transform_stamped(types, first, BASE_FRAME, CAMERA_FRAME, tour.mount)])
        write(tf_static, mount, first)
        for frame in tour.frames:
            s = frame.stamp_ns
            if base_source == "odom":
                write(odom, _odometry(types, s, frame.map_from_base), s)
            else:
                write(tf, types["tf2_msgs/msg/TFMessage"](transforms=[_transform_stamped(types, s, MAP_FRAME, BASE_FRAME, frame.map_from_base)]), s)
            write(info, _camera_info(types, tour, s), s)
            write(image, _image(types, frame.rgb, s), s)
    return path


__all__ = ["CAMERA_INFO_TOPIC", "IMAGE_TOPIC", "write_tour_bag"]
