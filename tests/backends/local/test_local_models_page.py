"""docs/how-to/local-models.md as a user runs it: the CPU loop's commands and `sft.py` exactly
as the page shows them (a tiny checkpoint, a one-house export, one training step), the tiny
checkpoint evaluated by the transformers backend, and the extras the page installs."""

from __future__ import annotations

import re
import runpy
import shlex
import sys
import tomllib
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app

pytestmark = pytest.mark.timeout(240)


@pytest.fixture(scope="module", autouse=True)
def _needs_trl() -> None:
    """These tests need TRL: skipped without it. Imported when they run, not when the file is
    collected (every pytest-xdist worker collects every file)."""
    pytest.importorskip("trl")


ROOT = Path(__file__).resolve().parents[3]
PAGE = ROOT / "docs" / "how-to" / "local-models.md"


def blocks() -> list[str]:
    """Every code block of the page, in order."""
    return re.findall(r"```[a-z]*\n(.*?)```", PAGE.read_text(), re.S)


def block(first_line: str) -> str:
    """The code block of the page whose first line is ``first_line``."""
    for body in blocks():
        if body.startswith(first_line):
            return body
    raise AssertionError(f"{PAGE.name} has no code block starting {first_line!r}")


def povagent(line: str) -> str:
    """One ``povagent ...`` line of the page, run as the console script runs it (in this process)."""
    done = CliRunner().invoke(app, shlex.split(line)[1:])
    assert done.exit_code == 0, f"{line} failed:\n{done.output}\n{done.exception!r}"
    return done.output


def test_the_cpu_loop_runs_as_the_page_shows_it(tmp_path, monkeypatch):
    import datasets

    from povagent_plugins.backends.local_checkpoint import checkpoint_fingerprint

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(datasets.config, "HF_DATASETS_CACHE", tmp_path / "hf-datasets")  # the test's own cache
    monkeypatch.setenv("HF_HUB_OFFLINE", "1")  # nothing may be downloaded
    (tmp_path / "sft.py").write_text(block('"""Fine-tune'))
    for line in block("povagent tiny-model tiny-vlm\npovagent generate").splitlines():
        if line.startswith("povagent "):
            povagent(line)
        else:
            args = shlex.split(line)
            assert args[:2] == ["python", "sft.py"], line
            monkeypatch.setattr(sys, "argv", args[1:])
            runpy.run_path("sft.py", run_name="__main__")
    assert (tmp_path / "tiny-sft" / "config.json").is_file()
    assert checkpoint_fingerprint(tmp_path / "tiny-sft") != checkpoint_fingerprint(tmp_path / "tiny-vlm")  # trained


def test_the_tiny_checkpoint_is_evaluated_by_the_transformers_backend_as_the_page_shows(tmp_path, monkeypatch, mini_root):
    from povagent.results.rows import read_rows

    monkeypatch.chdir(tmp_path)
    assert "povagent tiny-model tiny-vlm\n" in blocks()  # the section's one command
    povagent("povagent tiny-model tiny-vlm")
    doc = yaml.safe_load(block("# tiny.yaml"))
    doc["dataset"]["path"] = str(mini_root)  # the quickstart's data: a release-layout set like this one
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(doc))
    povagent(block("povagent run tiny.yaml").strip())
    rows = read_rows(tmp_path / "runs" / "tiny" / "results.jsonl")
    assert len(rows) == 2 and all(r.model.startswith("./tiny-vlm#") for r in rows)
    assert all(r.status in ("answered", "parse_error") for r in rows)


def test_the_train_extra_holds_what_the_page_installs_for_training():
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    names = {re.split(r"[<>=!~\[; ]", r, maxsplit=1)[0].lower() for r in extras["train"]}
    assert {"trl", "datasets", "pyarrow"} <= names
    assert "pip install 'povagent[local,train]'" in PAGE.read_text()
    assert "pip install 'povagent[train]'" in (ROOT / "docs" / "how-to" / "training.md").read_text()


def test_a_tiny_checkpoint_is_never_written_into_a_folder_that_holds_something(tmp_path):
    (tmp_path / "kept.txt").write_text("a real checkpoint's file")
    done = CliRunner().invoke(app, ["tiny-model", str(tmp_path)])
    assert done.exit_code != 0 and "exists and is not an empty folder" in str(done.exception)
    assert [p.name for p in tmp_path.iterdir()] == ["kept.txt"]


def test_without_transformers_the_command_names_what_to_install(tmp_path, monkeypatch):
    from povagent.cli.tiny_checkpoint import build_tiny_checkpoint
    from povagent.errors import PovagentError

    monkeypatch.setitem(sys.modules, "transformers", None)  # import transformers now fails, as when it is missing
    with pytest.raises(PovagentError, match=r"needs torch and transformers .*pip install 'povagent\[local\]'"):
        build_tiny_checkpoint(tmp_path / "tiny")
