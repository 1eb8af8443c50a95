"""Saving the keyframe memory to a folder and loading it back; a folder is untrusted input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from povagent.errors import ConfigError
from povagent.ros.camera_info import Intrinsics
from povagent.ros.keyframes import Keyframe, KeyframeMemory, MemorySettings
from povagent.ros.memory_folder import MEMORY_FILE, load_memory, save_memory


def memory_with_two_frames() -> KeyframeMemory:
    rng = np.random.default_rng(1)
    memory = KeyframeMemory(MemorySettings(min_translation=0.25, max_frames=7))
    for i in range(2):
        pose = np.eye(4)
        c, s = math.cos(i), math.sin(i)
        pose[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        pose[:3, 3] = (i * 1.0, 2.0, 0.5)
        depth = rng.uniform(0.5, 4, size=(6, 8)) if i else None
        rgb = rng.integers(0, 255, size=(12, 16, 3), dtype=np.uint8)
        memory.offer(Keyframe(10**9 * (i + 1), rgb, Intrinsics(20.0, 21.0, 8.0, 6.0, 16, 12).camera(pose, "ros"), depth, "cam"))
    return memory


def test_a_saved_memory_loads_back_frame_for_frame(tmp_path):
    memory = memory_with_two_frames()
    save_memory(memory, tmp_path / "mem")
    loaded = load_memory(tmp_path / "mem")
    assert loaded.settings == memory.settings and len(loaded) == 2
    for a, b in zip(memory.frames, loaded.frames):
        assert (a.stamp_ns, a.frame_id) == (b.stamp_ns, b.frame_id)
        assert np.array_equal(a.rgb, b.rgb)
        assert np.array_equal(a.camera.camera_to_world, b.camera.camera_to_world)
        assert (a.camera.fx, a.camera.fy, a.camera.cx, a.camera.cy, a.camera.convention) == (
            b.camera.fx,
            b.camera.fy,
            b.camera.cx,
            b.camera.cy,
            b.camera.convention,
        )
        assert (a.depth is None) == (b.depth is None)
    assert np.allclose(memory.frames[1].depth, loaded.frames[1].depth, atol=1e-6)


def test_a_loaded_memory_goes_on_from_its_newest_frame(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    loaded = load_memory(tmp_path / "mem")
    newest = loaded.frames[-1]
    loaded.offer(Keyframe(5, newest.rgb, newest.camera, None))  # same pose as the newest: not kept
    assert len(loaded) == 2


def edit(folder, change):
    path = folder / MEMORY_FILE
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


def test_a_file_name_leading_outside_the_folder_is_refused_naming_the_field(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    edit(tmp_path / "mem", lambda d: d["frames"][0].update(image="../../etc/passwd.png"))
    with pytest.raises(ConfigError, match=r"memory.json: field frames.0.image"):
        load_memory(tmp_path / "mem")


def test_a_pose_that_is_not_a_rigid_motion_is_refused_naming_the_frame(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    edit(tmp_path / "mem", lambda d: d["frames"][1].update(camera_to_map=[[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]))
    with pytest.raises(ConfigError, match=r"frames\[1\].camera_to_map: .*orthonormal"):
        load_memory(tmp_path / "mem")


def test_a_missing_image_is_refused_naming_it(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    (tmp_path / "mem" / "frame_0001.png").unlink()
    with pytest.raises(ConfigError, match=r"frames\[1\].image: cannot read frame_0001.png"):
        load_memory(tmp_path / "mem")


def test_a_folder_without_a_memory_says_so(tmp_path):
    with pytest.raises(ConfigError, match="no saved keyframe memory"):
        load_memory(tmp_path)


def test_a_pickled_depth_file_is_not_loaded(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    np.save(tmp_path / "mem" / "depth_0001.npy", np.array([{"x": 1}], dtype=object), allow_pickle=True)
    with pytest.raises(ConfigError, match=r"frames\[1\].depth"):
        load_memory(tmp_path / "mem")


def test_links_planted_in_an_earlier_memory_are_replaced_and_the_files_they_point_at_untouched(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    outside = {name: tmp_path / f"precious_{name}" for name in ("frame_0000.png", "depth_0001.npy", "frame_0001.png")}
    for name, target in outside.items():
        target.write_bytes(b"someone else's bytes")
        (tmp_path / "mem" / name).unlink()
        (tmp_path / "mem" / name).symlink_to(target)
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    assert all(target.read_bytes() == b"someone else's bytes" for target in outside.values())
    assert not any((tmp_path / "mem" / name).is_symlink() for name in outside)
    assert len(load_memory(tmp_path / "mem")) == 2


def test_a_folder_holding_someone_elses_files_is_refused_in_one_line_and_left_untouched(tmp_path):
    folder = tmp_path / "notes"
    folder.mkdir()
    (folder / "thesis.tex").write_text("mine")
    (folder / "frame_0000.png").symlink_to(tmp_path / "elsewhere.png")
    before = {p.name: (p.is_symlink(), p.read_text() if not p.is_symlink() else "") for p in folder.iterdir()}
    with pytest.raises(ConfigError) as info:
        save_memory(memory_with_two_frames(), folder)
    assert str(info.value).startswith(f"{folder}: not empty and not a saved keyframe memory") and "\n" not in str(info.value)
    assert {p.name: (p.is_symlink(), p.read_text() if not p.is_symlink() else "") for p in folder.iterdir()} == before
    assert not (tmp_path / "elsewhere.png").exists()


def test_a_memory_json_planted_as_a_link_is_not_taken_for_an_earlier_memory(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "real")
    folder = tmp_path / "planted"
    folder.mkdir()
    (folder / MEMORY_FILE).symlink_to(tmp_path / "real" / MEMORY_FILE)
    with pytest.raises(ConfigError, match="not empty and not a saved keyframe memory"):
        save_memory(memory_with_two_frames(), folder)


def test_saving_a_smaller_memory_over_an_earlier_one_removes_the_frames_it_no_longer_names(tmp_path):
    save_memory(memory_with_two_frames(), tmp_path / "mem")
    one = memory_with_two_frames()
    one.restore(one.frames[:1])
    save_memory(one, tmp_path / "mem")
    assert sorted(p.name for p in (tmp_path / "mem").iterdir()) == ["frame_0000.png", MEMORY_FILE]


def test_a_pipe_planted_as_the_memory_file_is_refused_in_one_line_never_waited_on(tmp_path):
    import os

    folder = tmp_path / "mem"
    folder.mkdir()
    os.mkfifo(folder / MEMORY_FILE)  # no writer: an ordinary open would wait for one forever
    with pytest.raises(ConfigError, match="not a regular file") as refused:
        load_memory(folder)
    assert "\n" not in str(refused.value) and MEMORY_FILE in str(refused.value)


def test_a_keyframe_image_linked_to_a_device_is_refused_naming_the_frame(tmp_path):
    import os

    memory = memory_with_two_frames()
    save_memory(memory, tmp_path / "mem")
    image = json.loads((tmp_path / "mem" / MEMORY_FILE).read_text())["frames"][0]["image"]
    (tmp_path / "mem" / image).unlink()
    os.symlink("/dev/zero", tmp_path / "mem" / image)  # reading it would fill memory
    with pytest.raises(ConfigError, match=r"frames\[0\]\.image: .*link"):
        load_memory(tmp_path / "mem")
