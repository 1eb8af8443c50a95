"""A ``rescore`` killed with SIGKILL mid-way never leaves part of its rows: the folder it writes
holds the previous complete rescore (or nothing), and the next rescore writes every key once."""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import pytest

from povagent.results.rows import iter_rows

#: Rows of the run: five answered instances of the hand-made set.
ANSWERS = [
    ("train_house_00000/0/right/a", '{"selected_image": 1, "x": 200, "y": 300}'),
    ("train_house_00000/0/right/b", '{"selected_image": 0, "x": 100, "y": 100}'),
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200}'),
    ("train_house_00000/0/left/a", '{"selected_image": 2, "x": 10, "y": 20}'),
    ("train_house_00000/0/left/c", '{"x": 256, "y": 256}'),
]

#: A scorer that, from its third row on, says so in a file and waits to be killed.
STALLING_SCORER = '''
import os, time
from pathlib import Path
from povagent import hookimpl
from povagent.interfaces import Scorer

class Stall(Scorer):
    calls = 0
    def score(self, instance, answer, dataset=None):
        Stall.calls += 1
        if Stall.calls >= 3 and os.environ.get("STALL_MARKER"):
            Path(os.environ["STALL_MARKER"]).write_text("stalled")
            time.sleep(120)
        return {"answered": True}

@hookimpl
def register_scorers(register):
    register("stall", Stall)
'''


def rescore(forks, run, *args, env=None):
    """``povagent rescore RUN ARGS`` started in a process of its own (tests/run/command_forks.py)."""
    return forks.start("rescore", run, *args, cwd=Path.cwd(), env=env)


@pytest.fixture
def stalled(tmp_path, write_answered_run, monkeypatch):
    """(run, plugin, the complete rescore's files as bytes) with the stall plugin beside the run.
    That complete rescore is made in this process (it only prepares the folder; the rescores
    under test run in processes of their own)."""
    from typer.testing import CliRunner

    from povagent.cli import app

    run = write_answered_run(tmp_path / "run", ANSWERS)
    plugin = tmp_path / "stall.py"
    plugin.write_text(STALLING_SCORER)
    monkeypatch.delenv("STALL_MARKER", raising=False)
    done = CliRunner().invoke(app, ["rescore", str(run), "--plugin", str(plugin), "--scorer", "stall"])
    assert done.exit_code == 0, f"{done.output}\n{done.exception!r}"
    out = run / "rescored-official"
    return run, plugin, {name: (out / name).read_bytes() for name in ("results.jsonl", "summary.json", "config.yaml")}


def killed_when_stalled(forks, run, plugin, marker):
    """A rescore with the stall scorer, SIGKILLed once it has stalled on its third row (``marker`` written)."""
    proc = rescore(forks, run, "--plugin", str(plugin), "--scorer", "stall", env={**os.environ, "STALL_MARKER": str(marker)})
    try:
        deadline = time.monotonic() + 120
        while not marker.exists():
            assert proc.poll() is None, proc.stderr()
            assert time.monotonic() < deadline, "the rescore never reached its third row"
            time.sleep(0.01)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    return proc


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="SIGKILL is POSIX-only")
def test_a_rescore_killed_mid_way_leaves_the_previous_complete_folder_and_the_next_writes_every_key_once(stalled, tmp_path, command_forks):
    # one kill serves both checks (each rescore child costs CPU): what the kill
    # left, then what the next rescore over that very folder writes
    run, plugin, complete = stalled
    proc = killed_when_stalled(command_forks, run, plugin, tmp_path / "stalled")
    assert proc.returncode == -signal.SIGKILL
    out = run / "rescored-official"
    # two rows were rescored when it died: none of them is in the file, the old rows all are
    for name, data in complete.items():
        assert (out / name).read_bytes() == data, f"the kill changed the previous complete rescore's {name}"

    again = rescore(command_forks, run, env={k: v for k, v in os.environ.items() if k != "STALL_MARKER"})
    assert again.wait(timeout=120) == 0, again.stderr()
    keys = [row.key for row in iter_rows(out / "results.jsonl")]
    assert sorted(keys) == sorted(f"{iid}#0" for iid, _ in ANSWERS), f"the rescore after the kill wrote {keys}"
    assert json.loads((out / "summary.json").read_text())["n_rows"] == len(ANSWERS), "the summary after the kill"
    assert not (out / "results.jsonl.tmp").exists(), "a staged file left after the rescore that followed the kill"


def test_a_failing_rescore_keeps_the_previous_folder_and_no_staged_file(stalled, tmp_path, command_forks):
    run, _, complete = stalled
    broken = tmp_path / "broken.py"
    broken.write_text(STALLING_SCORER.replace("Path(os.environ[\"STALL_MARKER\"]).write_text(\"stalled\")\n            time.sleep(120)",
                                              "raise RuntimeError('a scorer bug')").replace(' and os.environ.get("STALL_MARKER")', ""))
    done = rescore(command_forks, run, "--plugin", str(broken), "--scorer", "stall")
    assert done.wait(timeout=120) != 0
    assert "a scorer bug" in done.stderr()
    out = run / "rescored-official"
    for name, data in complete.items():
        assert (out / name).read_bytes() == data, name
    assert not (out / "results.jsonl.tmp").exists()
