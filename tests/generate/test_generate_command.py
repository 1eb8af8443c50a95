"""``povagent generate`` writes a dataset and says what it wrote."""

from __future__ import annotations

from typer.testing import CliRunner

from povagent.cli import app


def test_the_generate_command_writes_a_valid_dataset(tmp_path):
    from povagent.dataset.validate import validate_dataset

    result = CliRunner().invoke(app, ["generate", "--out", str(tmp_path), "--houses", "1", "--seed", "3", "--frames", "2"])
    assert result.exit_code == 0, result.output
    assert "1 houses" in result.output
    assert validate_dataset(tmp_path) == []
