"""MMSI-Bench's ``MMSI_Bench.parquet`` read as the set publishes it, and refused row by row where it is bad."""

from __future__ import annotations

import shutil

import pytest

from povagent.dataset.choice_sets import load_choice_set, validate_choice_set
from povagent.dataset.choice_sets.mmsi_records import inline_options
from povagent.errors import DatasetError

from .conftest import MMSI_ROWS, mmsi_rows, noise_photo, write_mmsi_parquet


def _load(path, tmp_path):
    """The set read, its embedded images written under the test's own folder."""
    return load_choice_set(path, "mmsi", cache_dir=tmp_path / "cache")


def test_every_row_is_read_with_its_options_gold_and_task_type(mmsi_parquet, tmp_path):
    loaded = _load(mmsi_parquet, tmp_path)
    assert loaded.problems == []
    read = [(i.pair_id, i.question.category, tuple(t for _, t in i.question.options), i.question.gold) for i in loaded.instances()]
    assert read == [(str(index), kind, options, gold) for index, kind, options, gold in MMSI_ROWS]


def test_the_question_is_asked_as_written_options_inside(mmsi_parquet, tmp_path):
    first = _load(mmsi_parquet, tmp_path).instances()[0]
    assert first.question.question.endswith("Options: A: Front left, B: Front right, C: Back left, D: Back right")
    assert first.question.profile == "mmsi"


def test_each_row_s_images_are_its_embedded_bytes_in_order(mmsi_parquet, tmp_path):
    rows = mmsi_rows()
    for instance, row in zip(_load(mmsi_parquet, tmp_path).instances(), rows):
        assert [frame.file.read_bytes() for frame in instance.frames] == row["images"]
    sizes = [len(b) for row in rows for b in row["images"]]
    assert min(sizes) > 100_000  # photographs' weight, not thumbnails


def test_a_question_shows_its_images_at_their_sizes(mmsi_parquet, tmp_path):
    msr = _load(mmsi_parquet, tmp_path).instances()[-1]
    assert [(f.camera.width, f.camera.height) for f in msr.frames] == [(640, 480), (400, 300), (512, 384)]


def test_a_datasets_image_column_is_read_as_the_plain_one(tmp_path):
    rows = mmsi_rows()[:3]
    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows, image_type="struct")
    loaded = _load(path, tmp_path)
    assert loaded.problems == [] and [[f.file.read_bytes() for f in i.frames] for i in loaded.instances()] == [r["images"] for r in rows]


def test_the_folder_holding_the_file_may_be_named(mmsi_parquet, tmp_path):
    assert len(_load(mmsi_parquet.parent, tmp_path).instances()) == len(MMSI_ROWS)


def _broken(row, case):
    if case == "not-an-image":
        row["images"][1] = b"GIF89a" + b"\0" * 100
    elif case == "truncated-png":
        row["images"][1] = row["images"][1][:5000]
    elif case == "no-options":
        row["question"] = "Where is the chair?"
    elif case == "gold-not-an-option":
        row["answer"] = "E"
    elif case == "no-images":
        row["images"] = []
    elif case == "too-many-images":
        row["images"] = [row["images"][0]] * 65
    elif case == "empty-type":
        row["question_type"] = " "
    return row


BROKEN = {  # case: the field the one problem names
    "not-an-image": "row 2.images[1]", "truncated-png": "record 1.images[1]", "no-options": "row 2.question",
    "gold-not-an-option": "row 2.answer", "no-images": "row 2.images", "too-many-images": "row 2.images",
    "empty-type": "row 2.question_type",
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(BROKEN))
def test_a_bad_row_is_one_problem_naming_file_and_field_and_the_rest_is_read(tmp_path, case):
    rows = mmsi_rows()[:4]
    rows[1] = _broken(rows[1], case)
    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows)
    loaded = _load(path, tmp_path)
    assert [(p.file, p.json_path) for p in loaded.problems] == [(str(path), BROKEN[case])]
    assert [i.pair_id for i in loaded.instances()] == ["0", "2", "3"]


def test_a_repeated_id_is_a_problem_and_the_first_row_is_kept(tmp_path):
    rows = mmsi_rows()[:3]
    rows[2]["id"] = 0
    loaded = _load(write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows), tmp_path)
    assert [(p.json_path, p.message) for p in loaded.problems] == [("row 3.id", "'0' is used by an earlier row; this one left out")]
    assert [i.pair_id for i in loaded.instances()] == ["0", "1"]


def test_a_file_that_is_not_parquet_is_one_line(tmp_path):
    path = tmp_path / "MMSI_Bench.parquet"
    path.write_bytes(noise_photo(1, (64, 48)))
    with pytest.raises(DatasetError, match=r"MMSI_Bench\.parquet: not a Parquet file") as caught:
        _load(path, tmp_path)
    assert "\n" not in str(caught.value)
    assert [p.file for p in validate_choice_set(path, "mmsi")] == [str(path)]


def test_a_parquet_file_without_the_set_s_columns_names_them(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = tmp_path / "MMSI_Bench.parquet"
    pq.write_table(pa.table({"id": [1], "question": ["q"]}), path)
    with pytest.raises(DatasetError, match="no column images, question_type, answer"):
        _load(path, tmp_path)


def test_a_row_group_declaring_more_than_the_bound_is_refused_before_it_is_decoded(tmp_path, monkeypatch):
    from povagent.dataset.choice_sets import mmsi_records as mmsi

    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", mmsi_rows()[:6])  # row groups of 4 and 2 rows
    monkeypatch.setattr(mmsi, "MAX_ROW_GROUP_BYTES", 2_000_000)  # the 4-row group holds over 2 MB of images
    monkeypatch.setattr(mmsi, "EXPANSION", 0)
    loaded = _load(path, tmp_path)
    assert [p.json_path for p in loaded.problems] == ["rows 1-4"]
    assert [i.pair_id for i in loaded.instances()] == ["4", "5"]


def test_validate_decodes_every_embedded_image(mmsi_parquet, tmp_path):
    copy = tmp_path / "MMSI_Bench.parquet"
    shutil.copy(mmsi_parquet, copy)
    assert validate_choice_set(copy, "mmsi") == []


@pytest.mark.parametrize(("question", "options"), [
    ("Q?\nOptions: A: left, B: right", (("A", "left"), ("B", "right"))),
    ("Q?\nOptions: A: Rotated 90 degrees, clockwise, B: No rotation", (("A", "Rotated 90 degrees, clockwise"), ("B", "No rotation"))),
    ("Is A: the cup? Options: A: yes, B: no, C: maybe", (("A", "yes"), ("B", "no"), ("C", "maybe"))),
    ("Q?\nOptions: B: left, A: right", ()),
    ("Q? A: left, B: right", ()),
])  # fmt: skip
def test_the_options_are_the_labelled_run_after_the_last_options_mark(question, options):
    assert inline_options(question) == options


def test_a_truncated_file_is_one_line(tmp_path, mmsi_parquet):
    path = tmp_path / "MMSI_Bench.parquet"
    path.write_bytes(mmsi_parquet.read_bytes()[: mmsi_parquet.stat().st_size // 2])
    (problem,) = validate_choice_set(path, "mmsi")
    assert problem.file == str(path) and problem.message.startswith("not a Parquet file") and "\n" not in problem.message


def test_a_corrupt_page_leaves_its_row_group_out_in_one_line_and_the_rest_is_read(tmp_path):
    import pyarrow.parquet as pq

    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", mmsi_rows()[:6])
    data = bytearray(path.read_bytes())
    at = pq.ParquetFile(path).metadata.row_group(0).column(0).data_page_offset + 2  # inside the first page's header
    data[at : at + 8] = bytes(b ^ 0xFF for b in data[at : at + 8])
    path.write_bytes(bytes(data))
    loaded = _load(path, tmp_path)
    assert [(p.json_path, "cannot be decoded" in p.message) for p in loaded.problems] == [("row 1", True)]
    assert [i.pair_id for i in loaded.instances()] == ["4", "5"]


def test_an_image_declaring_more_pixels_than_allowed_is_never_decoded(tmp_path):
    import struct
    import zlib

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    bomb = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", 100_000, 100_000, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(b"\0" * 64))
        + chunk(b"IEND", b"")
    )
    rows = mmsi_rows()[:2]
    rows[0]["images"][0] = bomb
    loaded = _load(write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows), tmp_path)
    (problem,) = loaded.problems
    assert problem.json_path == "record 0.images[0]" and "more than the" in problem.message
    assert [i.pair_id for i in loaded.instances()] == ["1"]


def test_a_pipe_named_as_the_file_is_never_waited_on(tmp_path):
    import os

    fifo = tmp_path / "MMSI_Bench.parquet"
    os.mkfifo(fifo)
    with pytest.raises(DatasetError, match=r"MMSI_Bench\.parquet: not found \(dataset\.path"):
        _load(fifo, tmp_path)


def test_the_bound_grows_with_the_file_so_a_sound_file_is_never_refused(tmp_path, monkeypatch):
    from povagent.dataset.choice_sets import mmsi_records as mmsi

    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", mmsi_rows()[:6])
    monkeypatch.setattr(mmsi, "MAX_ROW_GROUP_BYTES", 1)  # only the file-size bound is left
    loaded = _load(path, tmp_path)
    assert loaded.problems == [] and len(loaded.instances()) == 6
