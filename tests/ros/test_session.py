"""The session the node and the replay share: messages to keyframes, malformed input counted once
per kind, every command answered with a typed status."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from povagent.agent import GroundingAgent
from povagent.errors import NoAnswerError, UnparseableAnswerError
from povagent.geometry.goals import Plane
from povagent.ros.session import GroundingSession, agent_locate
from povagent.ros.transforms import RigidTransform

S = 1_000_000_000
W, H = 8, 6


def stamp(ns: int) -> SimpleNamespace:
    return SimpleNamespace(sec=ns // S, nanosec=ns % S)


def header(ns: int, frame: str) -> SimpleNamespace:
    return SimpleNamespace(stamp=stamp(ns), frame_id=frame)


def image(ns: int, encoding: str = "rgb8", frame: str = "cam_optical_frame") -> SimpleNamespace:
    return SimpleNamespace(header=header(ns, frame), height=H, width=W, encoding=encoding, step=W * 3, is_bigendian=0, data=bytes(W * H * 3))


def info(k=None) -> SimpleNamespace:
    return SimpleNamespace(header=header(0, "cam_optical_frame"), width=W, height=H, k=k or [10.0, 0, 3.5, 0, 10.0, 2.5, 0, 0, 1], d=[],
                           distortion_model="plumb_bob", binning_x=0, binning_y=0, roi=SimpleNamespace(width=0, height=0))


def odom(ns: int, x: float, nan: bool = False) -> SimpleNamespace:
    pose = SimpleNamespace(position=SimpleNamespace(x=float("nan") if nan else x, y=0.0, z=0.0), orientation=SimpleNamespace(x=0.0, y=0.0, z=0.0, w=1.0))
    return SimpleNamespace(header=header(ns, "map"), child_frame_id="base_link", pose=SimpleNamespace(pose=pose))


def pitched_down_mount(degrees: float) -> RigidTransform:
    """base_link -> optical frame: a camera 1 m up, looking along the base's x, tilted down."""
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2] = (0.0, -1.0, 0.0), (-s, 0.0, -c), (c, 0.0, -s)  # right, down, forward
    m[:3, 3] = (0.0, 0.0, 1.0)
    return RigidTransform.from_matrix(m)


@pytest.fixture(scope="module")
def centre_agent():
    """The offline ``center`` baseline (frame 0, its centre pixel) on a z-up map's floor."""
    with GroundingAgent(plane=Plane.horizontal(0.0, up_axis="z")) as agent:
        yield agent


@pytest.fixture
def session(centre_agent):
    problems = []
    s = GroundingSession(agent_locate(centre_agent), on_problem=lambda kind, message, first: problems.append((kind, first)))
    s.add_static("base_link", "cam_optical_frame", pitched_down_mount(45.0))
    s.reported = problems
    return s


def test_an_image_with_calibration_and_pose_becomes_a_keyframe_in_the_map(session):
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    [kept] = session.memory.frames
    assert np.allclose(kept.camera.position, [2.0, 0.0, 1.0]) and kept.camera.cx == 4.0
    assert np.allclose(kept.camera.ray(np.array([4.0, 3.0])), [math.sqrt(0.5), 0.0, -math.sqrt(0.5)])


def test_an_image_whose_transform_comes_later_waits_for_it(session):
    session.on_camera_info(info())
    session.on_image(image(S))
    assert len(session.memory) == 0
    session.on_odometry(odom(S, 2.0))
    assert len(session.memory) == 1 and not session.problems


def test_each_kind_of_malformed_message_is_counted_and_reported_first_once(session):
    session.on_camera_info(info(k=[float("nan")] * 9))
    session.on_camera_info(info())
    session.on_image(image(S, encoding="yuv422"))
    session.on_image(image(S, encoding="yuv422"))
    zero = image(S)
    zero.width = 0
    session.on_image(zero)
    session.on_odometry(odom(S, 0.0, nan=True))
    assert dict(session.problems) == {"camera_info": 1, "encoding": 2, "size": 1, "transform": 1}
    assert session.reported.count(("encoding", True)) == 1 and ("encoding", False) in session.reported


def test_an_image_before_its_calibration_waits_for_it_and_becomes_a_keyframe(session):
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    assert len(session.memory) == 0
    session.on_camera_info(info())
    [kept] = session.memory.frames
    assert kept.stamp_ns == S and kept.camera.cx == 4.0 and not session.problems


def test_images_waiting_for_a_calibration_are_bounded_the_oldest_dropped_and_counted(centre_agent):
    session = GroundingSession(agent_locate(centre_agent), max_pending=2)
    session.add_static("base_link", "cam_optical_frame", pitched_down_mount(45.0))
    for i in (1, 2, 3):
        session.on_odometry(odom(i * S, 2.0 * i))  # each pose far enough from the last to be kept
        session.on_image(image(i * S))
    assert session.problems["no_camera_info"] == 1
    session.on_camera_info(info())
    assert [f.stamp_ns for f in session.memory.frames] == [2 * S, 3 * S]


def test_the_end_of_a_bag_counts_images_that_never_had_a_calibration(session):
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    session.flush()
    assert session.problems["no_camera_info"] == 1 and len(session.memory) == 0


def test_with_no_goal_frame_given_the_first_odometry_messages_frame_is_the_goal_frame(centre_agent):
    decided = []
    session = GroundingSession(agent_locate(centre_agent), map_frame="", on_goal_frame=decided.append)
    session.add_static("base_link", "cam_optical_frame", pitched_down_mount(45.0))
    session.on_camera_info(info())
    session.on_image(image(S))  # waits: no goal frame yet
    in_odom = odom(S, 2.0)
    in_odom.header.frame_id = "odom"
    session.on_odometry(in_odom)
    later = odom(2 * S, 4.0)  # a second odometry in another frame changes nothing
    session.on_odometry(later)
    assert decided == ["odom"] and session.map_frame == "odom"
    assert len(session.memory) == 1 and np.allclose(session.memory.frames[0].camera.position, [2.0, 0.0, 1.0])
    result = session.answer("the mug")
    assert result.status == "ok" and result.map_frame == "odom"


def test_a_goal_frame_given_is_kept_whatever_frame_the_odometry_is_in(session):
    in_odom = odom(S, 2.0)
    in_odom.header.frame_id = "odom"
    session.on_odometry(in_odom)
    assert session.map_frame == "map"


def test_an_image_with_no_transform_near_its_stamp_is_given_up_once_newer_transforms_come(session):
    session.on_camera_info(info())
    session.on_image(image(S))
    session.on_odometry(odom(5 * S, 0.0))
    assert session.problems["missing_transform"] == 1 and len(session.memory) == 0


def test_the_end_of_a_bag_gives_up_images_still_waiting(session):
    session.on_camera_info(info())
    session.on_image(image(S))
    session.flush()
    assert session.problems["missing_transform"] == 1


def test_an_image_of_another_size_than_its_calibration_is_refused(session):
    other = info()
    other.width = 16
    session.on_camera_info(other)
    session.on_image(image(S))
    assert session.problems["size_mismatch"] == 1


def test_a_command_before_any_keyframe_is_answered_no_keyframes(session):
    result = session.answer("the mug left of the sink")
    assert result.status == "no_keyframes" and result.keyframes == 0


def test_a_blank_command_is_answered_empty_command(session):
    assert session.answer("   ").status == "empty_command"


def test_a_command_is_answered_with_the_chosen_keyframes_stamp_and_the_goal(session):
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    result = session.answer("the mug")
    assert (result.status, result.frame_index, result.frame_stamp_ns, result.pixel) == ("ok", 0, S, (4.0, 3.0))
    assert np.allclose(result.goal, (3.0, 0.0, 0.0)) and np.allclose(result.viewpoint, (2.0, 0.0, 1.0))  # 1 m up, 45 degrees down


def test_a_pixel_whose_ray_misses_the_floor_is_answered_no_goal_with_the_pixel(centre_agent):
    session = GroundingSession(agent_locate(centre_agent))
    session.add_static("base_link", "cam_optical_frame", pitched_down_mount(-10.0))  # looking up: the centre ray never meets the floor
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    result = session.answer("the lamp")
    assert result.status == "no_goal" and result.pixel == (4.0, 3.0) and result.goal is None and result.reason


@pytest.mark.parametrize(("error", "status"), [(NoAnswerError("timeout"), "no_answer"), (UnparseableAnswerError("no point", "blah"), "unparseable")])
def test_a_failed_answer_is_a_typed_status_not_silence(session, error, status):
    def fail(*args):
        raise error

    session.locate = fail
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    result = session.answer("the mug")
    assert result.status == status and str(error) in result.reason


def depth_image(ns: int, metres: float) -> SimpleNamespace:
    values = np.full((H, W), metres, dtype="<f4")
    return SimpleNamespace(header=header(ns, "cam_optical_frame"), height=H, width=W, encoding="32FC1", step=W * 4, is_bigendian=0, data=values.tobytes())


def test_a_depth_image_with_the_images_stamp_makes_the_goal_the_measured_point(session):
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_depth(depth_image(S, 0.5))  # the floor would be 1.41 m along the ray: the depth says 0.5 m
    session.on_image(image(S))
    result = session.answer("the mug")
    assert result.goal_method == "depth"
    assert np.allclose(result.goal, (2.0 + 0.5 * math.sqrt(0.5), 0.0, 1.0 - 0.5 * math.sqrt(0.5)))


def test_a_depth_image_of_another_stamp_is_not_used(session):
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_depth(depth_image(S + 1, 0.5))
    session.on_image(image(S))
    assert session.memory.frames[0].depth is None and session.answer("the mug").goal_method == "plane"


def test_a_compressed_image_takes_the_same_path_as_a_raw_one(session):
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.full((H, W, 3), 200, np.uint8)).save(buf, format="PNG")
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_compressed_image(SimpleNamespace(header=header(S, "cam_optical_frame"), format="png", data=buf.getvalue()))
    [kept] = session.memory.frames
    assert kept.rgb.shape == (H, W, 3) and int(kept.rgb.min()) == 200


def test_an_overlong_command_is_bad_input_and_never_reaches_the_model(session):
    from povagent.ros.session import MAX_COMMAND_CHARS

    def must_not_be_called(*args):
        raise AssertionError("the model was asked")

    session.locate = must_not_be_called
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    result = session.answer("x" * (MAX_COMMAND_CHARS + 1))
    assert result.status == "bad_input" and len(result.command) < 300


def test_every_command_shows_the_agent_each_keyframes_own_shown_frame(session):
    """What one command computed of a keyframe (letterbox, name, encoding) the next reuses."""
    shown = []

    def record(sentence, frames, cameras, depths):
        shown.append(list(frames))
        raise NoAnswerError("recorded")

    session.locate = record
    session.on_camera_info(info())
    session.on_odometry(odom(S, 2.0))
    session.on_image(image(S))
    session.answer("the mug")
    session.answer("the kettle")
    [kept] = session.memory.frames
    assert shown[0][0] is kept.shown and shown[1][0] is kept.shown
