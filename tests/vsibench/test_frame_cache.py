"""Sampled frames kept across runs: a second load of a set decodes no video, writes the very
bytes a decode writes, and an entry that is corrupt, truncated or of another video is ignored
(one log line naming it) and decoded again; entries are keyed by the video's bytes."""

from __future__ import annotations

import logging
import shutil

import pytest
import yaml

from povagent.dataset import video_frames
from povagent.dataset.choice_sets.vsibench_set import load_vsibench
from povagent.dataset.frame_cache import FrameCache, cached_sample_frames, video_digest
from povagent.errors import ConfigError, DatasetError

from .conftest import LEVEL_STEP, grey_level, write_video


def _frame_bytes(loaded) -> dict[str, list[bytes]]:
    return {i.id: [f.file.read_bytes() for f in i.frames] for i in loaded.instances()}


def _entries(folder):
    return sorted(folder.glob("*.frames"))


def test_a_second_load_decodes_no_video(vsibench_folder, tmp_path):
    kept = tmp_path / "frame-cache"
    before = video_frames.videos_opened()
    load_vsibench(vsibench_folder / "test.jsonl", frames=8, cache_dir=tmp_path / "c1", frame_cache=kept)
    first = video_frames.videos_opened() - before
    load_vsibench(vsibench_folder / "test.jsonl", frames=8, cache_dir=tmp_path / "c2", frame_cache=kept)
    assert first == 4 and video_frames.videos_opened() - before == first  # two scenes, each counted then decoded once
    assert len(_entries(kept)) == 2


def test_frames_from_the_cache_are_the_bytes_a_decode_writes(vsibench_folder, tmp_path):
    plain = load_vsibench(vsibench_folder / "test.jsonl", frames=6, cache_dir=tmp_path / "plain")
    load_vsibench(vsibench_folder / "test.jsonl", frames=6, cache_dir=tmp_path / "c1", frame_cache=tmp_path / "kept")
    cached = load_vsibench(vsibench_folder / "test.jsonl", frames=6, cache_dir=tmp_path / "c2", frame_cache=tmp_path / "kept")
    assert _frame_bytes(cached) == _frame_bytes(plain)
    scannet = cached.instance("vsibench/6")
    assert [round(grey_level(f.file) / LEVEL_STEP) for f in scannet.frames] == [0, 3, 6, 9, 12, 16]


def test_another_frame_count_is_another_entry(tmp_path):
    video = write_video(tmp_path / "scene.mp4", 12)
    cache = FrameCache(tmp_path / "kept")
    cached_sample_frames(video, 4, tmp_path / "a", cache)
    before = video_frames.videos_opened()
    files = cached_sample_frames(video, 3, tmp_path / "b", cache)
    assert video_frames.videos_opened() > before and len(_entries(tmp_path / "kept")) == 2
    assert [round(grey_level(f) / LEVEL_STEP) for f in files] == [0, 5, 11]


def test_the_key_is_the_video_s_bytes_not_its_path(tmp_path):
    video = write_video(tmp_path / "one" / "scene.mp4", 10)
    cache = FrameCache(tmp_path / "kept")
    cached_sample_frames(video, 4, tmp_path / "a", cache)
    shutil.copy(video, tmp_path / "elsewhere.mp4")
    before = video_frames.videos_opened()
    cached_sample_frames(tmp_path / "elsewhere.mp4", 4, tmp_path / "b", cache)
    assert video_frames.videos_opened() == before  # a copy hits
    write_video(video, 11)  # replaced under the same name: decoded again
    files = cached_sample_frames(video, 4, tmp_path / "c", cache)
    assert video_frames.videos_opened() > before and [round(grey_level(f) / LEVEL_STEP) for f in files] == [0, 3, 6, 10]


@pytest.mark.parametrize(
    ("damage", "says"),
    [
        (lambda data: data[: len(data) // 2], "truncated"),
        (lambda data: data[:-100] + bytes(100), "does not match its digest"),
        (lambda data: b"junk" + data, "not a frame cache entry"),
        (lambda data: data[:40], "not JSON"),
        (lambda data: data + b"x", "after its last frame"),
    ],
)
def test_a_corrupt_entry_is_named_in_one_line_and_the_video_decoded_again(tmp_path, caplog, damage, says):
    video = write_video(tmp_path / "scene.mp4", 12)
    cache = FrameCache(tmp_path / "kept")
    good = [f.read_bytes() for f in cached_sample_frames(video, 4, tmp_path / "a", cache)]
    (entry,) = _entries(tmp_path / "kept")
    entry.write_bytes(damage(entry.read_bytes()))
    before = video_frames.videos_opened()
    with caplog.at_level(logging.WARNING, logger="povagent.frame_cache"):
        files = cached_sample_frames(video, 4, tmp_path / "b", cache)
    assert [f.read_bytes() for f in files] == good and video_frames.videos_opened() > before
    (line,) = [r.getMessage() for r in caplog.records]
    assert str(entry) in line and says in line and "\n" not in line
    assert [f.read_bytes() for f in cached_sample_frames(video, 4, tmp_path / "c", cache)] == good  # rewritten: a hit again


def test_an_entry_of_another_video_under_this_one_s_name_is_ignored(tmp_path, caplog):
    one, two = write_video(tmp_path / "one.mp4", 12), write_video(tmp_path / "two.mp4", 9)
    cache = FrameCache(tmp_path / "kept")
    cached_sample_frames(two, 4, tmp_path / "a", cache)
    (entry,) = _entries(tmp_path / "kept")
    entry.rename(tmp_path / "kept" / cache.entry_name(video_digest(one), 4))
    with caplog.at_level(logging.WARNING, logger="povagent.frame_cache"):
        files = cached_sample_frames(one, 4, tmp_path / "b", cache)
    assert [round(grey_level(f) / LEVEL_STEP) for f in files] == [0, 3, 7, 11]
    assert "another video" in caplog.records[0].getMessage()


def test_an_entry_that_is_a_link_is_not_followed(tmp_path, caplog):
    video = write_video(tmp_path / "scene.mp4", 12)
    cache = FrameCache(tmp_path / "kept")
    cached_sample_frames(video, 4, tmp_path / "a", cache)
    (entry,) = _entries(tmp_path / "kept")
    outside = tmp_path / "outside.frames"
    entry.rename(outside)
    entry.symlink_to(outside)
    with caplog.at_level(logging.WARNING, logger="povagent.frame_cache"):
        cached_sample_frames(video, 4, tmp_path / "b", cache)
    assert "symbolic link" in caplog.records[0].getMessage()
    assert not entry.is_symlink()  # the new entry was renamed over the link, never written through it
    assert outside.read_bytes()[:17] == b"povagent-frames 1"


def test_entries_are_written_whole_nothing_else_left_in_the_folder(vsibench_folder, tmp_path):
    load_vsibench(vsibench_folder / "test.jsonl", frames=3, cache_dir=tmp_path / "c", frame_cache=tmp_path / "kept")
    assert [p.suffix for p in sorted((tmp_path / "kept").iterdir())] == [".frames", ".frames"]


def test_the_pipeline_option_names_the_cache_folder(vsibench_folder, tmp_path):
    from povagent.config.pipeline import load_pipeline
    from povagent.dataset.evaluation_set import open_evaluation_set

    options = {"frames": 4, "cache_dir": str(tmp_path / "kept")}
    config = {"dataset": {"path": str(vsibench_folder / "test.jsonl"), "format": "vsibench", "options": options},
              "backend": "oracle", "output": str(tmp_path / "run")}  # fmt: skip
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(config))
    loaded = load_pipeline(tmp_path / "p.yaml")
    dataset = loaded.dataset
    open_evaluation_set(dataset.root, format=dataset.format, images=dataset.images, options=dataset.options)
    assert len(_entries(tmp_path / "kept")) == 2


def test_a_cache_dir_that_is_a_file_is_refused_naming_the_option(vsibench_folder, tmp_path):
    from povagent.dataset.evaluation_set import open_evaluation_set

    (tmp_path / "kept").write_text("")
    with pytest.raises((DatasetError, ConfigError), match="cache_dir"):
        open_evaluation_set(vsibench_folder / "test.jsonl", format="vsibench", options={"cache_dir": str(tmp_path / "kept")})


def test_validate_keeps_the_frames_in_the_folder_it_is_given(vsibench_folder, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    args = ["validate", str(vsibench_folder / "test.jsonl"), "--format", "vsibench", "--frame-cache", str(tmp_path / "kept")]
    assert CliRunner().invoke(app, args).exit_code == 0 and len(_entries(tmp_path / "kept")) == 2
    before = video_frames.videos_opened()
    assert CliRunner().invoke(app, args).exit_code == 0 and video_frames.videos_opened() == before


def test_validate_refuses_a_frame_cache_for_a_set_without_videos(tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    (tmp_path / "data.json").write_text("[]")
    result = CliRunner().invoke(app, ["validate", str(tmp_path / "data.json"), "--format", "omnispatial", "--frame-cache", str(tmp_path / "kept")])
    assert result.exit_code == 2 and "--frame-cache" in result.output and not (tmp_path / "kept").exists()
