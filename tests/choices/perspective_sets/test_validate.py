"""``povagent validate F --format NAME`` names every bad record of a set, one line each, and a
path leading out of the set's folder is refused, never opened."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from povagent.cli import app
from povagent.dataset.choice_sets import load_choice_set, validate_choice_set


def _validate(file, format):
    return CliRunner().invoke(app, ["validate", str(file), "--format", format])


def test_a_sound_set_is_valid(set_file):
    result = _validate(set_file("mindcube"), "mindcube")
    assert result.exit_code == 0 and result.output.strip().endswith(": valid")


def test_validate_names_each_bad_viewspatial_record_by_file_record_and_field(set_file):
    file = set_file("viewspatial")
    records = json.loads(file.read_text())
    records[1]["answer"] = "E. nowhere"  # no standalone A-D: the official rule reads no gold
    del records[2]["choices"]
    file.write_text(json.dumps(records))
    result = _validate(file, "viewspatial")
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert lines[:2] == [
        f"{file}: $[1].answer: 'E. nowhere' names no label A-D (the official rule reads the first standalone letter)",
        f"{file}: $[2].choices: required, a non-empty string",
    ]
    assert lines[2:] == [f"2 problem(s) in {file}"]  # the count, on stderr


def test_validate_names_a_mindcube_line_whose_markers_do_not_match_its_images(set_file):
    file = set_file("mindcube")
    lines = file.read_text().splitlines()
    record = json.loads(lines[2])
    record["images"] = record["images"][:2]
    file.write_text("\n".join([lines[0], "{not json", json.dumps(record)]) + "\n")
    problems = [str(p) for p in validate_choice_set(file, "mindcube")]
    assert problems == [
        f"{file}: line 2: not valid JSON: Expecting property name enclosed in double quotes at column 2",
        f"{file}: line 3.question: holds 3 <image> marker(s) for 2 image(s); give each image its marker, or none (the images then go first)",
    ]


def test_a_3dsrbench_image_that_is_not_base64_is_refused_and_named(set_file):
    file = set_file("3dsrbench")
    lines = file.read_text().splitlines()
    cells = lines[5].split("\t")
    cells[-1] = "!!not an image!!" * 5  # over 64 characters: VLMEvalKit reads a shorter cell as an index
    lines[5] = "\t".join(cells)
    file.write_text("\n".join(lines) + "\n")
    problems = [str(p) for p in validate_choice_set(file, "3dsrbench")]
    assert len(problems) == 2  # the record, and its flipped copy reusing its image by index
    assert problems[0].startswith(f"{file}: line 6.image: the image is not valid base64")
    assert problems[1].startswith(f"{file}: line 7.image: names the record of index '4', and no record of that index holds an image")


def test_an_image_path_leading_out_of_the_sets_folder_is_refused_and_never_opened(set_file, tmp_path):
    secret = tmp_path / "secret.png"
    secret.write_bytes(b"not even read")
    file = set_file("viewspatial")
    records = json.loads(file.read_text())
    records[0]["image_path"] = ["../secret.png"]
    records[3]["image_path"] = [str(secret)]
    file.write_text(json.dumps(records))
    loaded = load_choice_set(file, "viewspatial")
    assert [i.pair_id for i in loaded.instances()] == ["1", "2"]
    assert [(p.json_path, p.message) for p in loaded.problems] == [
        ("$[0].images[0]", "image path '../secret.png' leads outside the dataset folder; not opened"),
        (
            "$[3].images[0]",
            f"image path {str(secret)!r} is absolute: paths in a dataset are relative to the house folder and stay inside the dataset; not opened",
        ),
    ]


def test_a_symlink_leading_out_of_the_sets_folder_is_refused(set_file, tmp_path):
    outside = tmp_path / "outside.png"
    (set_file("mindcube").parent / "images" / "room_2.png").rename(outside)
    (set_file("mindcube").parent / "images" / "room_2.png").symlink_to(outside)
    loaded = load_choice_set(set_file("mindcube"), "mindcube")
    assert [p.message for p in loaded.problems] == ["image path 'images/room_2.png' leads outside the dataset folder through a symlink; not opened"]
    assert len(loaded.instances()) == 2


def test_an_over_long_tsv_line_is_refused_without_reading_it_whole(set_file, monkeypatch):
    from povagent.dataset.choice_sets import external

    monkeypatch.setattr(external, "MAX_RECORD_LINE_BYTES", 180)  # line 6 embeds its image: 205 bytes
    problems = [str(p) for p in validate_choice_set(set_file("3dsrbench"), "3dsrbench")]
    assert problems == [f"{set_file('3dsrbench')}: line 6: longer than 180 bytes; this line and the rest of the file are not read"]


def test_each_viewspatial_record_repeating_an_answer_text_reads_its_own_gold_or_problem(set_file):
    from povagent.dataset.choice_sets.viewspatial_records import read_viewspatial

    file = set_file("viewspatial")
    records = json.loads(file.read_text())
    assert len(records) >= 4
    records[1]["answer"] = records[3]["answer"] = "E. nowhere"  # read once, told for each record
    records[0]["answer"] = records[2]["answer"] = "B. " + records[0]["choices"].splitlines()[1][3:]
    file.write_text(json.dumps(records))
    items, problems = read_viewspatial(file)
    assert [(p.json_path, p.message[:24]) for p in problems] == [("$[1].answer", "'E. nowhere' names no la"), ("$[3].answer", "'E. nowhere' names no la")]
    assert [i.question.gold for i in items[:2]] == ["B", "B"]
