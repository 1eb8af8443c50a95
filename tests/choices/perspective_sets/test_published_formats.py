"""The three sets' files as published, at their real sizes: 3DSRBench's TSV with embedded
images of a few hundred KB (over the ``csv`` module's 128 KiB field limit), MindCube's raw
records with no ``<image>`` marker, ViewSpatial-Bench's JSON with its repository-relative paths.

Every image is made here from numpy noise, so it does not compress: a PNG or JPEG of a few
hundred KB, as the real sets' are.
"""

from __future__ import annotations

import base64
import csv
import io
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from povagent.config.pipeline import load_pipeline
from povagent.dataset.choice_sets import load_choice_set
from povagent.dataset.choice_sets.mindcube_records import category_of
from povagent.dataset.choice_sets.srbench3d_records import MAX_CELL_CHARS, tsv_cells
from povagent.run.runner import run_pipeline

HEADER = "index\tqid\tquestion\tA\tB\tC\tD\tanswer\tcategory\timage"


def noise_image(kind: str, width: int, height: int, seed: int) -> bytes:
    """An image of random pixels (incompressible), encoded as ``kind`` (PNG or JPEG)."""
    pixels = np.random.default_rng(seed).integers(0, 256, (height, width, 3), dtype=np.uint8)
    out = io.BytesIO()
    Image.fromarray(pixels).save(out, format=kind, **({"quality": 95} if kind == "JPEG" else {}))
    return out.getvalue()


def tsv_line(index: int, qid: str, answer: str, category: str, image: str) -> str:
    return f"{index}\t{qid}\tIs the lamp higher than the clock?\tyes\tno\tnan\t\t{answer}\t{category}\t{image}"


@pytest.fixture
def real_size_tsv(tmp_path) -> tuple[Path, dict[str, bytes]]:
    """A 3DSRBench TSV of three records: 0 with an embedded PNG, 1 naming record 2's image by
    its index before record 2 comes, 2 with an embedded JPEG."""
    png, jpeg = noise_image("PNG", 320, 240, 1), noise_image("JPEG", 640, 480, 2)
    lines = [
        HEADER,
        tsv_line(0, "QUES0001", "A", "height_higher", base64.b64encode(png).decode()),
        tsv_line(1, "QUES0002-flip", "B", "height_higher", "2"),
        tsv_line(2, "QUES0002", "A", "height_higher", base64.b64encode(jpeg).decode()),
    ]
    file = tmp_path / "3DSRBench.tsv"
    file.write_text("\n".join(lines) + "\n")
    return file, {"png": png, "jpeg": jpeg}


def test_the_fixture_images_are_real_sized_and_their_cells_beyond_the_csv_field_limit(real_size_tsv):
    _, images = real_size_tsv
    assert all(len(data) > 200_000 for data in images.values())
    assert all(len(base64.b64encode(data)) > csv.field_size_limit() for data in images.values())


def test_3dsrbench_reads_embedded_images_of_a_few_hundred_kb(real_size_tsv):
    file, images = real_size_tsv
    loaded = load_choice_set(file, "3dsrbench")
    assert loaded.problems == []
    by_id = {i.pair_id: i for i in loaded.instances()}
    assert by_id["QUES0001"].frames[0].file.read_bytes() == images["png"] and by_id["QUES0001"].frame_size == (320, 240)
    assert by_id["QUES0002"].frames[0].file.read_bytes() == images["jpeg"] and by_id["QUES0002"].frame_size == (640, 480)


def test_3dsrbench_an_image_cell_naming_a_later_record_shows_that_record_s_image(real_size_tsv):
    # VLMEvalKit reads a cell of 64 characters or fewer as an index into the whole file
    loaded = load_choice_set(real_size_tsv[0], "3dsrbench")
    by_id = {i.pair_id: i for i in loaded.instances()}
    assert by_id["QUES0002-flip"].frames[0].file == by_id["QUES0002"].frames[0].file
    assert [i.pair_id for i in loaded.instances()] == ["QUES0001", "QUES0002-flip", "QUES0002"]  # file order kept


def test_3dsrbench_an_image_cell_naming_no_record_is_one_problem(tmp_path):
    png = base64.b64encode(noise_image("PNG", 64, 48, 3)).decode()
    file = tmp_path / "3DSRBench.tsv"
    file.write_text("\n".join([HEADER, tsv_line(0, "QUES0001", "A", "height_higher", png), tsv_line(1, "QUES0003", "A", "height_higher", "7")]) + "\n")
    loaded = load_choice_set(file, "3dsrbench")
    assert [str(p) for p in loaded.problems] == [
        f"{file}: line 3.image: names the record of index '7', and no record of that index holds an image (a path or base64); record left out"
    ]
    assert [i.pair_id for i in loaded.instances()] == ["QUES0001"]


def test_3dsrbench_a_cell_over_the_bound_is_one_line_naming_file_line_and_column(tmp_path):
    png = base64.b64encode(noise_image("PNG", 64, 48, 4)).decode()
    file = tmp_path / "3DSRBench.tsv"
    file.write_text("\n".join([HEADER, tsv_line(0, "QUES0001", "A", "height_higher", "Q" * (MAX_CELL_CHARS + 1)),
                               tsv_line(1, "QUES0002", "A", "height_higher", png)]) + "\n")  # fmt: skip
    loaded = load_choice_set(file, "3dsrbench")
    assert [str(p) for p in loaded.problems] == [
        f"{file}: line 2.image: a cell of {MAX_CELL_CHARS + 1} characters, over the {MAX_CELL_CHARS} a cell may hold; record left out"
    ]
    assert [i.pair_id for i in loaded.instances()] == ["QUES0002"]


def test_3dsrbench_a_cell_at_the_bound_is_read(tmp_path):
    file = tmp_path / "3DSRBench.tsv"
    question = "Q" * MAX_CELL_CHARS
    file.write_text(
        "\n".join([HEADER, tsv_line(0, "QUES0001", "A", "height_higher", "img.png").replace("Is the lamp higher than the clock?", question)]) + "\n"
    )
    Image.new("RGB", (4, 3)).save(tmp_path / "img.png")
    loaded = load_choice_set(file, "3dsrbench")
    assert loaded.problems == [] and len(loaded.instances()[0].question.question) == MAX_CELL_CHARS


@pytest.mark.parametrize("line", [
    'a\tb\tc', '"a\tb"\tc', '"say ""yes"""\tx', '"a"tail\tb', 'mid"quote\t"x"', '\t\t', '""\t"\t"',
])  # fmt: skip
def test_3dsrbench_splits_a_line_as_the_csv_module_reads_it(line):
    assert tsv_cells(line) == next(csv.reader([line], delimiter="\t"))


def test_3dsrbench_a_quote_never_closed_is_one_problem(tmp_path):
    file = tmp_path / "3DSRBench.tsv"
    file.write_text("\n".join([HEADER, '0\tQUES0001\t"open\tyes\tno\tnan\t\tA\theight_higher\timg.png']) + "\n")
    assert [str(p) for p in load_choice_set(file, "3dsrbench").problems] == [f"{file}: line 2: a quoted cell (cell 3) is never closed; record left out"]


def _mindcube_record(record_id: str, images: list[str], gold: str, question: str | None = None) -> dict:
    text = question or "Based on these views, after turning left, what is in front of you? A. Sofa B. Lamp C. Window D. Door"
    return {"id": record_id, "category": ["self", "among"], "type": "cross_perspective", "meta_info": [], "question": text, "images": images, "gt_answer": gold}


@pytest.fixture
def mindcube_raw(tmp_path) -> Path:
    """MindCube's own layout: ``data/raw/MindCube_tinybench.jsonl``, images named from ``data/``,
    raw records (no ``<image>`` marker), real-size JPEGs."""
    data = tmp_path / "data"
    (data / "raw").mkdir(parents=True)
    (data / "other_all_image" / "among" / "group1").mkdir(parents=True)
    names = []
    for k in range(4):
        name = f"other_all_image/among/group1/view{k}.jpg"
        (data / name).write_bytes(noise_image("JPEG", 512, 384, 10 + k))
        names.append(name)
    records = [_mindcube_record("among_group1_q1_1_2", names, "B"), _mindcube_record("translation_group1_q1", names[:2], "A")]
    converted = dict(records[0], input_prompt=records[0]["question"] + "\nAnswer:", grounded_output="B. Lamp")
    (data / "raw" / "MindCube_tinybench.jsonl").write_text("".join(json.dumps(r) + "\n" for r in [*records]))
    (data / "raw" / "converted.jsonl").write_text(json.dumps(converted | {"id": "around_group2_q1"}) + "\n")
    return data


def test_mindcube_reads_a_raw_record_with_no_image_marker(mindcube_raw):
    loaded = load_choice_set(mindcube_raw / "raw" / "MindCube_tinybench.jsonl", "mindcube", images=mindcube_raw)
    assert loaded.problems == []
    first = loaded.instances()[0]
    assert len(first.frames) == 4 and first.frame_size == (512, 384)
    assert first.question.options == (("A", "Sofa"), ("B", "Lamp"), ("C", "Window"), ("D", "Door")) and first.question.gold == "B"


def test_mindcube_reads_a_converted_record_with_its_prompt_fields(mindcube_raw):
    loaded = load_choice_set(mindcube_raw / "raw" / "converted.jsonl", "mindcube", images=mindcube_raw)
    assert loaded.problems == [] and loaded.instances()[0].question.category == "around"


@pytest.mark.parametrize(("record_id", "setting"), [
    ("among_group1_q1_1_2", "among"), ("aroundnew_0012_q3", "around"), ("translation_group1_q1", "translation"),
    ("rotation_0003_q2", "rotation"), ("other_0001", "other"), ("Around_0001", "around"),
])  # fmt: skip
def test_mindcube_reads_the_setting_from_the_id_as_its_evaluator_does(record_id, setting):
    assert category_of(record_id) == setting


def test_a_raw_mindcube_record_is_asked_with_its_images_first(mindcube_raw, tmp_path, offline_plugin_file):
    import yaml

    config = {
        "plugins": [str(offline_plugin_file)],
        "dataset": {"path": str(mindcube_raw / "raw" / "MindCube_tinybench.jsonl"), "format": "mindcube", "images": str(mindcube_raw)},
        "backend": "oracle", "strategy": "choice", "scorers": ["choice"], "runs": 1, "timeout": 5, "output": str(tmp_path / "run"),
    }  # fmt: skip
    path = tmp_path / "mindcube.yaml"
    path.write_text(yaml.safe_dump(config))
    result = run_pipeline(load_pipeline(path))
    assert result.summary.metrics["choice"].overall["accuracy"].value == 1.0
    from povagent.results.rows import read_rows

    (first, _) = read_rows(result.run_dir / "results.jsonl")
    assert len(first.exchanges[-1].image_hashes) == 4


@pytest.fixture
def viewspatial_repository(tmp_path) -> Path:
    """ViewSpatial-Bench's repository layout: ``eval/ViewSpatial-Bench.json`` naming images from
    the repository root (``ViewSpatial-Bench/scannetv2_val/...``)."""
    repo = tmp_path / "ViewSpatial-Bench-repo"
    scene = repo / "ViewSpatial-Bench" / "scannetv2_val" / "scene0011_00" / "original_images"
    scene.mkdir(parents=True)
    (scene / "280.jpg").write_bytes(noise_image("JPEG", 640, 480, 20))
    (repo / "eval").mkdir()
    record = {
        "question_type": "Camera perspective - Relative Direction",
        "image_path": ["ViewSpatial-Bench/scannetv2_val/scene0011_00/original_images/280.jpg"],
        "question": "Could you tell me the location of the counter in comparison to the refrigerator?",
        "answer": "A. right", "choices": "A. right\nB. front-up\nC. back-left\nD. front",
    }  # fmt: skip
    (repo / "eval" / "ViewSpatial-Bench.json").write_text(json.dumps([record], indent=2))
    return repo


def test_viewspatial_reads_the_repository_folder_with_its_root_relative_paths(viewspatial_repository):
    loaded = load_choice_set(viewspatial_repository, "viewspatial")
    assert loaded.problems == [] and loaded.instances()[0].frame_size == (640, 480)


def test_viewspatial_images_not_found_beside_the_file_say_where_the_paths_are_relative_to(viewspatial_repository):
    file = viewspatial_repository / "eval" / "ViewSpatial-Bench.json"
    (problem,) = load_choice_set(file, "viewspatial").problems
    assert str(problem) == (
        f"{file}: $[0].images[0]: image 'ViewSpatial-Bench/scannetv2_val/scene0011_00/original_images/280.jpg' does not exist "
        "(ViewSpatial-Bench's image paths are relative to its repository root: give the repository folder as dataset.path "
        "(the set's file is then its eval/ViewSpatial-Bench.json), or that root as dataset.images)"
    )
