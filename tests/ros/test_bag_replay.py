"""Bag replay: a generated house's tour written as a bag (sqlite3 and mcap, /tf or /odom) replays
to the goal the GroundingAgent finds for the same frames and cameras."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.errors import ConfigError
from povagent.ros.bag_replay import ReplayTopics, replay_bag
from povagent.ros.memory_folder import load_memory
from povagent.ros.session import GroundingSession
from povagent.ros.tour_bag import write_tour_bag

pytest.importorskip("rosbags", reason="the bags extra is not installed (pip install 'povagent[bags]')")

GOAL_TOLERANCE = 0.05  # simulated exact perception: the box fit's error (m), as examples/robot_app.py


@pytest.fixture(scope="module")
def direct(tour, simulated_locate):
    """What the agent answers for the tour's frames and cameras, given directly."""
    return simulated_locate(tour.truth.sentence, [f.rgb for f in tour.frames], tour.cameras(), [None] * len(tour.frames))


@pytest.mark.parametrize(("storage", "base_source"), [("sqlite3", "tf"), ("mcap", "odom")])
def test_a_replayed_bag_gives_the_agents_goal_and_the_ground_truth(tour, simulated_locate, direct, tmp_path, storage, base_source):
    bag = write_tour_bag(tour, tmp_path / "tour", storage=storage, base_source=base_source)
    session = GroundingSession(simulated_locate)
    replay_bag(bag, session)
    assert not session.problems and len(session.memory) == len(tour.frames)
    for kept, frame in zip(session.memory.frames, tour.frames):
        assert np.allclose(kept.camera.camera_to_world, frame.map_from_camera, atol=1e-9)
    result = session.answer(tour.truth.sentence)
    assert result.status == "ok" and result.frame_index == direct.frame_index
    assert np.allclose(result.goal, direct.goal.point, atol=1e-6, rtol=0)
    assert np.linalg.norm(np.array(result.goal) - np.array(tour.truth.target)) < GOAL_TOLERANCE


def test_the_memory_a_replay_keeps_follows_the_rule(tour, simulated_locate, tmp_path):
    from povagent.ros.keyframes import KeyframeMemory, MemorySettings

    bag = write_tour_bag(tour, tmp_path / "tour")
    settings = MemorySettings(max_frames=5)
    session = GroundingSession(simulated_locate, settings=settings)
    replay_bag(bag, session)
    expected = KeyframeMemory(settings)
    for camera, frame in zip(tour.cameras(), tour.frames):
        from povagent.ros.keyframes import Keyframe

        expected.offer(Keyframe(frame.stamp_ns, frame.rgb, camera))
    assert [f.stamp_ns for f in session.memory.frames] == [f.stamp_ns for f in expected.frames] and len(session.memory) == 5


def test_a_replayed_memory_saves_and_loads_to_the_same_goal(tour, simulated_locate, direct, tmp_path):
    from povagent.ros.memory_folder import save_memory

    session = GroundingSession(simulated_locate)
    replay_bag(write_tour_bag(tour, tmp_path / "tour"), session)
    save_memory(session.memory, tmp_path / "memory")
    again = GroundingSession(simulated_locate, memory=load_memory(tmp_path / "memory"))
    assert np.allclose(again.answer(tour.truth.sentence).goal, direct.goal.point, atol=1e-6, rtol=0)


def test_a_bag_without_the_image_topic_names_the_topics_it_has(tour, simulated_locate, tmp_path):
    bag = write_tour_bag(tour, tmp_path / "tour")
    with pytest.raises(ConfigError, match=r"no image topic '/cam/rgb' in the bag \(topics: .*/camera/image_raw"):
        replay_bag(bag, GroundingSession(simulated_locate), ReplayTopics(image="/cam/rgb"))


def test_a_folder_that_is_not_a_bag_is_one_error_naming_it(tmp_path, simulated_locate):
    (tmp_path / "notabag").mkdir()
    (tmp_path / "notabag" / "metadata.yaml").write_text("rosbag2_bagfile_information: [unclosed")
    with pytest.raises(ConfigError, match="notabag: cannot open the bag"):
        replay_bag(tmp_path / "notabag", GroundingSession(simulated_locate))


def test_a_damaged_record_in_a_bag_is_counted_and_the_replay_goes_on(tour, simulated_locate, tmp_path):
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    with Writer(tmp_path / "damaged", version=9) as writer:
        image = writer.add_connection("/camera/image_raw", "sensor_msgs/msg/Image", typestore=store)
        writer.write(image, 1, b"\x00\x01\x00\x00\x07")  # a CDR header and then too few bytes for an Image
    session = GroundingSession(simulated_locate)
    replay_bag(tmp_path / "damaged", session)
    assert session.problems["deserialize"] == 1 and session.answer("x").status == "no_keyframes"


def write_bag(folder, topics, messages):
    """A bag at ``folder`` with ``topics`` (topic -> (type, typestore)) and ``messages`` ((topic, message) in order)."""
    from rosbags.rosbag2 import Writer

    with Writer(folder, version=9) as writer:
        connections = {topic: (writer.add_connection(topic, msgtype, typestore=store), msgtype, store) for topic, (msgtype, store) in topics.items()}
        for i, (topic, msg) in enumerate(messages):
            connection, msgtype, store = connections[topic]
            writer.write(connection, i + 1, store.serialize_cdr(msg, msgtype))
    return folder


def test_compressed_images_over_the_pixel_budget_are_counted_and_never_decoded(tmp_path, simulated_locate, claimed_png):
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    Compressed, Header, Time = (store.types[t] for t in ("sensor_msgs/msg/CompressedImage", "std_msgs/msg/Header", "builtin_interfaces/msg/Time"))
    png = np.frombuffer(claimed_png(6000, 6000), dtype=np.uint8)
    images = [
        ("/camera/image_raw/compressed", Compressed(header=Header(stamp=Time(sec=i, nanosec=0), frame_id="cam"), format="png", data=png)) for i in range(12)
    ]
    bag = write_bag(tmp_path / "huge", {"/camera/image_raw/compressed": ("sensor_msgs/msg/CompressedImage", store)}, images)
    session = GroundingSession(simulated_locate)
    replay_bag(bag, session, ReplayTopics(image="/camera/image_raw/compressed"))
    assert session.problems == {"pixel_budget": 12}


def test_a_message_of_another_type_under_a_known_topic_is_counted_not_a_traceback(tmp_path, simulated_locate):
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    String = store.types["std_msgs/msg/String"]
    topics = {"/camera/camera_info": ("std_msgs/msg/String", store), "/camera/image_raw": ("sensor_msgs/msg/Image", store)}
    session = GroundingSession(simulated_locate)
    replay_bag(write_bag(tmp_path / "wrong", topics, [("/camera/camera_info", String(data="not a calibration"))]), session)
    assert session.problems == {"message_type": 1}


def test_a_bag_defining_a_known_type_its_own_way_is_counted_not_a_traceback(tmp_path, simulated_locate):
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    own = get_typestore(Stores.EMPTY)
    own.register(get_types_from_msg("string data", "sensor_msgs/msg/CameraInfo"))  # the bag carries this definition
    topics = {"/camera/camera_info": ("sensor_msgs/msg/CameraInfo", own), "/camera/image_raw": ("sensor_msgs/msg/Image", get_typestore(Stores.ROS2_JAZZY))}
    bag = write_bag(tmp_path / "own", topics, [("/camera/camera_info", own.types["sensor_msgs/msg/CameraInfo"](data="no K here"))])
    session = GroundingSession(simulated_locate)
    replay_bag(bag, session)
    assert session.problems == {"message_type": 1}


def test_a_metadata_file_with_a_python_tag_is_refused_in_one_line_and_runs_nothing(tmp_path, simulated_locate):
    bag = tmp_path / "tagged"
    bag.mkdir()
    (bag / "metadata.yaml").write_text(f"rosbag2_bagfile_information: !!python/object/apply:os.system ['touch {tmp_path / 'ran'}']\n")
    with pytest.raises(ConfigError) as info:
        replay_bag(bag, GroundingSession(simulated_locate))
    assert str(info.value).startswith(f"{bag}: cannot open the bag: ") and "python/object/apply" in str(info.value)
    assert "\n" not in str(info.value) and not (tmp_path / "ran").exists()
