"""Every command's ``--help`` explains itself: options in words, flags as flags, nothing
pointing into the source, and nothing wider than an 80-column terminal."""

from __future__ import annotations

import functools
import re

import pytest
import typer
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()
COMMANDS = sorted(typer.main.get_command(app).commands)  # type: ignore[attr-defined]


@functools.cache
def help_of(*args: str) -> str:
    """What ``povagent ARGS --help`` prints at 80 columns: asked once a module, read by each test
    of a command (the text is a string, so no test can change it for another)."""
    result = runner.invoke(app, [*args, "--help"], env={"COLUMNS": "80"})
    assert result.exit_code == 0, result.output
    return result.stdout


def options_section(text: str) -> str:
    return text.split("\nOptions:\n", 1)[1]


def test_every_command_is_checked():
    assert {"run", "sweep", "plugins", "score", "validate", "show-prompt", "download"} <= set(COMMANDS)


@pytest.mark.parametrize("command", COMMANDS)
def test_no_option_shows_a_type_placeholder(command):
    """Flags read as flags (``--strict``, not ``--strict <bool>``) and every option taking a value
    names it in words (``--output FOLDER``), never ``<path>``, ``<int>`` or ``<list[str]>``."""
    options = options_section(help_of(command))
    assert "<bool>" not in options
    assert re.findall(r"<[a-z][a-z\[\] ]*>", options) == []


@pytest.mark.parametrize("command", COMMANDS)
def test_no_help_points_into_the_source(command):
    text = help_of(command)
    assert re.findall(r"\bpovagent\.[a-z_]+", text) == [], text
    assert "``" not in text  # reStructuredText quoting belongs in docstrings read as source


@pytest.mark.parametrize("command", COMMANDS)
def test_every_option_and_argument_is_explained(command):
    params = typer.main.get_command(app).commands[command].params  # type: ignore[attr-defined]
    unexplained = [p.name for p in params if not (p.help or "").strip()]
    assert unexplained == []


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_help_fits_80_columns_and_the_command_list_is_not_cut(command):
    text = help_of(command) if command else help_of()
    assert max(len(line) for line in text.splitlines()) <= 80, text
    if command is None:
        listing = text.split("\nCommands:\n", 1)[1].splitlines()
        assert [line for line in listing if line.rstrip().endswith("...")] == []


def test_run_help_shows_its_flags_as_flags():
    options = options_section(help_of("run"))
    assert "--keep-errors / --retry-errors" in options and "[default: retry-errors]" in options
    assert re.search(r"^  --strict  +Stop at the first bad house", options, re.MULTILINE)
    assert re.search(r"^  -o, --output FOLDER  +Run folder", options, re.MULTILINE)


def test_keep_errors_has_its_opposite_spelled_out(tmp_path, mini_root):
    """``--retry-errors`` is accepted (the default said out loud), ``--keep-errors`` still works."""
    import yaml

    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center", "output": str(tmp_path / "run")}))
    for flag in ("--retry-errors", "--keep-errors"):
        result = runner.invoke(app, ["run", str(pipeline), "--quiet", "--json", "--limit", "3", flag])
        assert result.exit_code == 0, result.output


def test_show_prompt_help_gives_the_id_format_and_an_example():
    options = options_section(help_of("show-prompt"))
    assert "HOUSE/PAIR/DIRECTION/CONDITION" in options
    assert "train_house_00000/pair_000/right/a" in options  # as a generated set writes ids
