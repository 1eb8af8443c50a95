"""MMSI-Bench and OmniSpatial fixtures in the sets' published formats, made here at realistic sizes.

``mmsi_parquet``: ``MMSI_Bench.parquet`` as the set publishes it (columns ``id, images,
question_type, question, answer, thought``; ``images`` a list of encoded images' bytes), its
images noise photographs of a few hundred KB each, PNG and JPEG. ``omnispatial_folder``: the
unpacked ``OmniSpatial-test.zip`` (``data.json`` beside one folder per task type, an image per
question number, two questions sharing one). Nothing is copied from the sets.
"""

from __future__ import annotations

import functools
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

#: (id, question_type, options, gold): eleven MMSI-Bench questions over four task types
MMSI_ROWS = [
    (0, "Positional Relationship (Cam.-Obj.)", ("Front left", "Front right", "Back left", "Back right"), "A"),
    (1, "Positional Relationship (Cam.-Obj.)", ("Left", "Right", "Above", "Below"), "B"),
    (2, "Positional Relationship (Cam.-Obj.)", ("Closer", "Farther", "Same distance", "Cannot tell"), "C"),
    (3, "Positional Relationship (Obj.-Obj.)", ("The chair", "The lamp", "The sofa", "The table"), "D"),
    (4, "Positional Relationship (Obj.-Obj.)", ("North", "South", "East", "West"), "A"),
    (5, "Attribute (Meas.)", ("1.5 m", "2.0 m", "3.5 m", "0.5 m"), "B"),
    (6, "Attribute (Meas.)", ("About 10 cm", "About 30 cm", "About 1 m", "About 2 m"), "B"),
    (7, "Motion (Cam.)", ("Turned left, then moved forward", "Turned right", "Moved back", "Stayed"), "C"),
    (8, "Motion (Cam.)", ("Rotated 90 degrees, clockwise", "Rotated 180 degrees", "No rotation", "Rotated 45 degrees"), "A"),
    (9, "MSR", ("Kitchen", "Bedroom", "Bathroom", "Hallway"), "D"),
    (10, "MSR", ("Two", "Three", "Four", "Five"), "D"),
]  # fmt: skip

#: (id, task_type, sub_task_type, options, gold index): twelve OmniSpatial questions
OMNI_RECORDS = [
    ("0_0", "Perspective_Taking", "Egocentric", ("left", "right", "front", "back"), 0),
    ("0_1", "Perspective_Taking", "Egocentric", ("1", "2", "3", "4"), 1),
    ("1_0", "Perspective_Taking", "Egocentric", ("the cup", "the pot", "the pan", "the jug"), 2),
    ("2_0", "Perspective_Taking", "Allocentric", ("left", "right", "front", "back"), 1),
    ("3_0", "Perspective_Taking", "Allocentric", ("yes", "no"), 0),
    ("4_0", "Perspective_Taking", "Hypothetical", ("north", "south", "east", "west"), 3),
    ("5_0", "Perspective_Taking", "Hypothetical", ("2", "3", "4", "5"), 0),
    ("0_0", "Dynamic_Reasoning", "Motion_Analysis", ("2.7s", "14.7s", "25.7s", "3.9s"), 0),
    ("1_0", "Dynamic_Reasoning", "Manipulation", ("pull", "push", "lift", "twist"), 1),
    ("0_0", "Complex_Logic", "Geometric_Reasoning", ("A cube", "A cone", "A sphere", "A torus"), 2),
    ("0_0", "Spatial_Interaction", "Traffic_Analysis", ("stop", "go", "turn left", "turn right"), 3),
    ("1_0", "Spatial_Interaction", "Localization", ("here", "there", "nowhere", "everywhere"), 1),
]  # fmt: skip


@functools.cache
def noise_photo(seed: int, size: tuple[int, int] = (640, 480), kind: str = "JPEG") -> bytes:
    """An encoded image of noise over a gradient: incompressible enough to weigh what a photo does
    (a 640x480 JPEG of it is ~200-400 KB)."""
    rng = np.random.default_rng(seed)
    w, h = size
    base = np.linspace(0, 200, w, dtype=np.float32)[None, :, None] + np.zeros((h, 1, 3), np.float32)
    pixels = np.clip(base + rng.normal(0, 40, (h, w, 3)), 0, 255).astype(np.uint8)
    out = io.BytesIO()
    Image.fromarray(pixels).save(out, kind, **({"quality": 95} if kind == "JPEG" else {}))
    return out.getvalue()


def mmsi_question(options: tuple[str, ...], index: int) -> str:
    """A question written as the set writes it: the options inside, after ``Options:``."""
    listed = ", ".join(f"{chr(65 + k)}: {text}" for k, text in enumerate(options))
    return f"The images are taken continuously from a first-person view. Question {index}: where is it?\nOptions: {listed}"


def write_mmsi_parquet(path: Path, rows: list[dict[str, Any]], *, image_type: str = "binary") -> Path:
    """``rows`` (``id, images, question_type, question, answer, thought``) as a Parquet file;
    ``image_type``: ``binary`` (the set's file) or ``struct`` (a ``datasets`` Image column)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    if image_type == "struct":
        image = pa.struct([("bytes", pa.binary()), ("path", pa.string())])
        rows = [{**r, "images": [{"bytes": b, "path": None} for b in r["images"]]} for r in rows]
    else:
        image = pa.binary()
    schema = pa.schema([("id", pa.int64()), ("images", pa.list_(image)), ("question_type", pa.string()),
                        ("question", pa.string()), ("answer", pa.string()), ("thought", pa.string())])  # fmt: skip
    pq.write_table(pa.Table.from_pylist(rows, schema=schema), path, row_group_size=4)
    return path


def mmsi_rows() -> list[dict[str, Any]]:
    """The fixture's rows, two images each (one JPEG, one PNG), the last question three."""
    rows = []
    for index, kind, options, gold in MMSI_ROWS:
        images = [noise_photo(2 * index), noise_photo(2 * index + 1, (400, 300), "PNG")]
        if kind == "MSR":
            images.append(noise_photo(100 + index, (512, 384)))
        rows.append({"id": index, "images": images, "question_type": kind, "question": mmsi_question(options, index),
                     "answer": gold, "thought": "First, find the camera. Then compare."})  # fmt: skip
    return rows


@pytest.fixture(scope="session")
def mmsi_parquet(tmp_path_factory) -> Path:
    """The fixture's ``MMSI_Bench.parquet`` (made once a session; tests copy it to change it)."""
    folder = tmp_path_factory.mktemp("mmsi")
    return write_mmsi_parquet(folder / "MMSI_Bench.parquet", mmsi_rows())


def omnispatial_records() -> list[dict[str, Any]]:
    """The fixture's ``data.json`` records."""
    return [{"id": i, "question": f"From the person's view, which option holds for question {k}?", "options": list(options),
             "answer": gold, "task_type": task, "sub_task_type": sub}
            for k, (i, task, sub, options, gold) in enumerate(OMNI_RECORDS)]  # fmt: skip


def write_omnispatial(folder: Path, records: list[dict[str, Any]]) -> Path:
    """``records`` as ``folder/data.json``, with the image of every question number each names."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "data.json").write_text(json.dumps(records, indent=4), encoding="utf-8")
    for k, record in enumerate(records):
        if isinstance(record, dict) and isinstance(record.get("task_type"), str) and isinstance(record.get("id"), str):
            image = folder / record["task_type"] / f"{record['id'].split('_')[0]}.png"
            if not image.exists() and ".." not in record["task_type"]:
                image.parent.mkdir(parents=True, exist_ok=True)
                image.write_bytes(noise_photo(500 + k, (480, 360), "PNG"))
    return folder / "data.json"


@pytest.fixture(scope="session")
def omnispatial_folder(tmp_path_factory) -> Path:
    """The fixture's unpacked test split: ``data.json`` and its images (made once a session)."""
    folder = tmp_path_factory.mktemp("omnispatial") / "OmniSpatial-test"
    write_omnispatial(folder, omnispatial_records())
    return folder


#: What the ``offline_plugin_file`` fixture copies, for a run a module makes once.
OFFLINE_PLUGIN = Path(__file__).parents[2] / "run" / "offline_plugin.py"
