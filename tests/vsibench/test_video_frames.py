"""Frames of a scene video are the ones VSI-Bench's models take: linspace(0, total - 1, N)
truncated, decoded with PyAV from a video made here; a video that is no video is one line."""

from __future__ import annotations

import sys

import pytest

from povagent.dataset.video_frames import MISSING_PYAV, VideoError, count_frames, sample_frames, sample_indices
from povagent.errors import PovagentError

from .conftest import LEVEL_STEP, grey_level, write_video


def test_indices_spread_evenly_first_and_last_included_truncated_towards_zero():
    assert sample_indices(24, 8) == [0, 3, 6, 9, 13, 16, 19, 23]  # 23/7 = 3.2857: 3.29, 6.57, 9.86, 13.1 ...
    assert sample_indices(100, 1) == [0]


def test_more_frames_asked_than_the_video_has_repeat_frames_as_the_official_loader_does():
    assert sample_indices(3, 5) == [0, 0, 1, 1, 2]


def test_the_frames_written_are_the_frames_at_the_sampled_indices(tmp_path):
    video = write_video(tmp_path / "scene.mp4", 24)
    assert count_frames(video) == 24
    files = sample_frames(video, 8, tmp_path / "frames")
    assert [round(grey_level(f) / LEVEL_STEP) for f in files] == [0, 3, 6, 9, 13, 16, 19, 23]


def test_a_file_that_is_no_video_is_one_line(tmp_path):
    fake = tmp_path / "scene.mp4"
    fake.write_bytes(b"not a video at all" * 10)
    with pytest.raises(VideoError) as err:
        sample_frames(fake, 4, tmp_path / "frames")
    assert "\n" not in str(err.value)


def test_a_frame_count_outside_the_bound_is_refused(tmp_path):
    video = write_video(tmp_path / "scene.mp4", 4)
    with pytest.raises(VideoError, match="1 to 256"):
        sample_frames(video, 0, tmp_path / "frames")


def test_without_pyav_one_line_names_the_extra(tmp_path, monkeypatch):
    video = write_video(tmp_path / "scene.mp4", 4)
    monkeypatch.setitem(sys.modules, "av", None)  # import av now raises ImportError
    with pytest.raises(PovagentError) as err:
        count_frames(video)
    assert str(err.value) == MISSING_PYAV
    assert "povagent[video]" in MISSING_PYAV
