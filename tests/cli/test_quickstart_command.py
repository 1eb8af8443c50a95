"""``povagent quickstart``: baselines swept, table printed, report written, resumable."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


#: The model clients a run of offline baselines must never import (litellm takes seconds).
CLIENTS = ("litellm", "openai", "httpx", "tiktoken", "tokenizers")


@pytest.fixture(scope="module")
def quickstart(mini_root, tmp_path_factory) -> tuple[list[str], str, Path, str]:
    """(its arguments, what it printed, its folder, the model clients its process imported): one
    ``quickstart`` (a sweep of three baselines and a report) in a fresh process, as a user runs
    it, shared by the tests that read it or run it again (a fresh interpreter costs a second of
    CPU: one serves all three)."""
    import subprocess
    import sys

    out = tmp_path_factory.mktemp("quickstart") / "qs"
    args = ["quickstart", "--out", str(out), "--dataset", str(mini_root), "--quiet"]
    code = (
        "import sys\n"
        "from povagent.cli import main\n"
        f"sys.argv = ['povagent', *{args!r}]\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        f"print(sorted(m for m in {CLIENTS!r} if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    *printed, imported = done.stdout.strip().splitlines()
    return args, "\n".join(printed) + "\n" + done.stderr, out, imported


def test_quickstart_on_a_given_dataset_prints_the_main_table_and_writes_the_report(quickstart):
    _, output, out, _ = quickstart
    assert "| Baseline | Inferred | Stated | Given |" in output  # only baselines ran: no "Model" column
    oracle_line = next(line for line in output.splitlines() if "oracle" in line and line.startswith("|"))
    assert oracle_line.count("0.000") >= 3  # the oracle is the metric's floor: the pipeline is wired right
    assert (out / "sweep" / "report" / "report.html").exists()
    cells = json.loads((out / "sweep" / "sweep.json").read_text())
    assert len(cells["cells"]) == 3


def test_running_the_quickstart_again_makes_no_new_rows(quickstart):
    args, _, out, _ = quickstart
    files = sorted((out / "sweep").rglob("results.jsonl"))
    assert len(files) == 3, files
    before = [f.read_bytes() for f in files]
    assert runner.invoke(app, args).exit_code == 0
    assert [f.read_bytes() for f in files] == before


def test_the_quickstart_imports_no_model_client(quickstart):
    """Only offline baselines run: litellm (seconds to import) and its clients stay unimported,
    in a fresh process as a user runs it."""
    _, output, _, imported = quickstart
    assert imported == "[]", output[-500:]
