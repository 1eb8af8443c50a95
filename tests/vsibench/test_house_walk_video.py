"""A walk through a generated house is a scene video: its exploration frames, written as an mp4
with PyAV, are read as a VSI-Bench scene, and the frames a question shows are the walk's frames
at the set's sampled indices."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from povagent.dataset.choice_sets.vsibench_set import load_vsibench

from .conftest import av, write_jsonl


def write_walk(frames: list[Path], path: Path) -> Path:
    """The frames, in order, as an H.264 video (lossless quantiser: only the RGB-YUV round trip changes them)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with Image.open(frames[0]) as first:
        width, height = first.size
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=4)
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv444p"
        stream.options = {"qp": "0", "preset": "ultrafast"}
        for frame in frames:
            with Image.open(frame) as image:
                pixels = np.asarray(image.convert("RGB"))
            for packet in stream.encode(av.VideoFrame.from_ndarray(pixels, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def test_a_question_about_a_generated_house_shows_the_walks_frames_at_the_sampled_indices(generated_release, tmp_path):
    house = sorted((generated_release / "artifacts").iterdir())[0]
    walk = sorted((house / "exploration_images").glob("*.png"))
    assert len(walk) == 12
    write_walk(walk, tmp_path / "procthor" / f"{house.name}.mp4")
    record = {"id": 0, "dataset": "procthor", "scene_name": house.name, "question_type": "object_counting",
              "question": "How many bed(s) are in this room?", "options": None, "ground_truth": "1"}  # fmt: skip
    loaded = load_vsibench(write_jsonl(tmp_path / "test.jsonl", [record]), frames=4, cache_dir=tmp_path / "cache")
    assert loaded.problems == []
    [instance] = loaded.instances()
    # linspace(0, 11, 4) truncated: 0, 3, 7, 11
    for shown, index in zip(instance.frames, (0, 3, 7, 11), strict=True):
        assert difference(shown.file, walk[index]) < 2.0, (shown.index, index)
        assert difference(shown.file, walk[index - 1 if index else 1]) > 2.0  # a neighbouring frame of the walk is another view


def difference(a: Path, b: Path) -> float:
    """The mean absolute difference of two images' RGB values."""
    with Image.open(a) as one, Image.open(b) as other:
        return float(np.abs(np.asarray(one.convert("RGB"), dtype=int) - np.asarray(other.convert("RGB"), dtype=int)).mean())
