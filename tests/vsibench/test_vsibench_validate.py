"""``povagent validate FILE --format vsibench`` lists every record left out, one line each
naming file, record and field, and exits 1; a sound set is valid."""

from __future__ import annotations

from typer.testing import CliRunner

from povagent.cli import app

from .conftest import RECORDS, write_jsonl, write_video


def test_a_sound_set_is_valid(vsibench_folder):
    result = CliRunner().invoke(app, ["validate", str(vsibench_folder / "test.parquet"), "--format", "vsibench"])
    assert result.exit_code == 0, result.output
    assert "valid" in result.output


def test_each_record_left_out_is_one_line_and_the_exit_code_is_one(tmp_path):
    write_video(tmp_path / "arkitscenes" / "41069025.mp4", 4)
    file = write_jsonl(tmp_path / "test.jsonl", [RECORDS[0], {**RECORDS[1], "scene_name": "../../etc"}, RECORDS[6]])
    result = CliRunner().invoke(app, ["validate", str(file), "--format", "vsibench"])
    assert result.exit_code == 1
    lines = [line for line in result.output.splitlines() if line.startswith(str(file))]
    assert lines == [
        f"{file}: line 2.scene_name: required, a plain name (letters, digits, '_', '.', '-'; no '/'), got '../../etc'",
        f"{file}: record 6.scene_name: video 'scannet/scene0011_00.mp4' does not exist",
    ]
