"""``povagent validate FILE --format mmsi|omnispatial`` lists each bad record in one line and exits 1."""

from __future__ import annotations

import shutil

from typer.testing import CliRunner

from povagent.cli import app

from .conftest import mmsi_rows, omnispatial_records, write_mmsi_parquet, write_omnispatial


def test_a_sound_mmsi_file_validates(tmp_path, mmsi_parquet):
    shutil.copy(mmsi_parquet, tmp_path / "MMSI_Bench.parquet")
    result = CliRunner().invoke(app, ["validate", str(tmp_path / "MMSI_Bench.parquet"), "--format", "mmsi"])
    assert result.exit_code == 0, result.output


def test_a_bad_mmsi_row_is_one_line_naming_file_row_and_field(tmp_path):
    rows = mmsi_rows()[:3]
    rows[1]["images"][0] = b"GIF89a" + b"\0" * 10
    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows)
    result = CliRunner().invoke(app, ["validate", str(path), "--format", "mmsi"])
    assert result.exit_code == 1
    assert f"{path}: row 2.images[0]: neither a PNG nor a JPEG" in result.output.splitlines()


def test_a_bad_omnispatial_record_is_one_line_naming_file_record_and_field(tmp_path):
    records = omnispatial_records()[:3]
    records[2]["answer"] = 9
    write_omnispatial(tmp_path / "set", records)
    result = CliRunner().invoke(app, ["validate", str(tmp_path / "set"), "--format", "omnispatial"])
    assert result.exit_code == 1
    assert [line for line in result.output.splitlines() if "data.json: " in line] == [
        f"{tmp_path / 'set' / 'data.json'}: $[2].answer: required, the 0-based index of the gold option among 4 (got 9)"
    ]
