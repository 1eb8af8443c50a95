"""VSI-Bench fixtures made here: short scene videos written with PyAV (each frame a flat grey
whose level is its index times :data:`LEVEL_STEP`, so a test reads back which frame it got), and
a set in VSI-Bench's published shape (its columns, its ten question types), as JSONL and Parquet."""

from __future__ import annotations

import json
from pathlib import Path

import av  # the test extra installs PyAV (as the video extra does): a missing one fails, never skips
import numpy as np
import pytest

#: The grey level of frame i is ``i * LEVEL_STEP`` (0-255): 24 frames span 0-230.
LEVEL_STEP = 10
WIDTH, HEIGHT = 64, 48

#: Records in the published shape: every question type, two scenes, gold answers of each kind.
RECORDS = [
    {"id": 0, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "object_counting",
     "question": "How many chair(s) are in this room?", "options": None, "ground_truth": "4"},
    {"id": 1, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "object_abs_distance",
     "question": "Measuring from the closest point of each object, what is the direct distance between the table and the sofa (in meters)?",
     "options": None, "ground_truth": "1.8"},
    {"id": 2, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "object_size_estimation",
     "question": "What is the length of the longest dimension (length, width, or height) of the bed, measured in centimeters?",
     "options": None, "ground_truth": "203"},
    {"id": 3, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "room_size_estimation",
     "question": "What is the size of this room (in square meters)? If multiple rooms are shown, estimate the size of the combined space.",
     "options": None, "ground_truth": "22.4"},
    {"id": 4, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "object_rel_distance",
     "question": "Measuring from the closest point of each object, which of these objects (tv, lamp, stool) is the closest to the sofa?",
     "options": ["A. tv", "B. lamp", "C. stool"], "ground_truth": "B"},
    {"id": 5, "dataset": "arkitscenes", "scene_name": "41069025", "question_type": "object_rel_direction_easy",
     "question": "If I am standing by the sofa and facing the tv, is the lamp to my left or the right?",
     "options": ["A. left", "B. right"], "ground_truth": "A"},
    {"id": 6, "dataset": "scannet", "scene_name": "scene0011_00", "question_type": "object_rel_direction_medium",
     "question": "If I am standing by the desk and facing the door, is the bed to my left, right, or back?",
     "options": ["A. left", "B. right", "C. back"], "ground_truth": "C"},
    {"id": 7, "dataset": "scannet", "scene_name": "scene0011_00", "question_type": "object_rel_direction_hard",
     "question": "If I am standing by the desk and facing the door, is the bed to my front-left, front-right, back-left, or back-right?",
     "options": ["A. front-left", "B. front-right", "C. back-left", "D. back-right"], "ground_truth": "D"},
    {"id": 8, "dataset": "scannet", "scene_name": "scene0011_00", "question_type": "route_planning",
     "question": "You are a robot beginning at the door facing the bed. You want to navigate to the desk. [...] 1. Go forward until the bed 2. [please fill "
                 "in] 3. Go forward until the desk.",
     "options": ["A. Turn Left", "B. Turn Right", "C. Turn Back"], "ground_truth": "A"},
    {"id": 9, "dataset": "scannet", "scene_name": "scene0011_00", "question_type": "obj_appearance_order",
     "question": "What will be the first-time appearance order of the following categories in the video: bed, desk, door, chair?",
     "options": ["A. bed, desk, door, chair", "B. door, bed, chair, desk", "C. desk, door, bed, chair", "D. chair, bed, desk, door"],
     "ground_truth": "B"},
    {"id": 10, "dataset": "scannet", "scene_name": "scene0011_00", "question_type": "object_counting",
     "question": "How many pillow(s) are in this room?", "options": None, "ground_truth": "2"},
]  # fmt: skip


def write_video(path: Path, n_frames: int, fps: int = 24) -> Path:
    """An H.264 video of ``n_frames`` flat grey frames, frame i at grey level i * LEVEL_STEP."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=fps)
        stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "yuv420p"
        stream.options = {"qp": "0", "preset": "ultrafast"}  # lossless: the grey levels come back as written
        for i in range(n_frames):
            pixels = np.full((HEIGHT, WIDTH, 3), i * LEVEL_STEP, dtype=np.uint8)
            for packet in stream.encode(av.VideoFrame.from_ndarray(pixels, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def grey_level(png: Path) -> int:
    """The grey level of a flat frame read back (the frame's index is this / LEVEL_STEP)."""
    from PIL import Image

    with Image.open(png) as image:
        return int(round(float(np.asarray(image.convert("L")).mean())))


def write_jsonl(path: Path, records: list[dict]) -> Path:
    path.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    return path


def write_parquet(path: Path, records: list[dict]) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([("id", pa.int64()), ("dataset", pa.string()), ("scene_name", pa.string()), ("question_type", pa.string()),
                        ("question", pa.string()), ("options", pa.list_(pa.string())), ("ground_truth", pa.string())])  # fmt: skip
    pq.write_table(pa.Table.from_pylist(records, schema=schema), path)
    return path


@pytest.fixture
def vsibench_folder(tmp_path) -> Path:
    """A folder as the set is unpacked: ``test.jsonl``, ``test.parquet`` and the two scenes'
    videos (24 and 17 frames) under ``<dataset>/<scene_name>.mp4``."""
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 24)
    write_video(tmp_path / "scannet" / "scene0011_00.mp4", 17)
    write_jsonl(tmp_path / "test.jsonl", RECORDS)
    write_parquet(tmp_path / "test.parquet", RECORDS)
    return tmp_path
