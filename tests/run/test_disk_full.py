"""A disk that fills mid-run stops the run with one line, keeps every row written so far, and
after space is freed the same command resumes with every key exactly once.

On a real tmpfs of 64 KiB (mounted here when the test runs as root) the writes fail with
ENOSPC; under a file-size limit (RLIMIT_FSIZE) they fail with EFBIG. Rows hold multi-byte
characters (the dataset's sentences do), so the write the disk cut may end inside one.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
import yaml

pytestmark = [pytest.mark.timeout(180), pytest.mark.skipif(sys.platform != "linux", reason="tmpfs and RLIMIT_FSIZE: Linux")]

#: A row is about 4 KB, so 72 rows (about 290 KB) fill the 64 KiB disk and pass the 48 kB file
#: limit well before the run's end, at a few rows' CPU each.
RUNS = 4
#: Keys of the pipeline: the two good houses hold 18 instances.
KEYS = 18 * RUNS


@pytest.fixture
def pipeline(tmp_path, dataset_copy) -> Path:
    """A pipeline (built-in center baseline) over the two good houses, whose sentences now hold
    2-, 3- and 4-byte characters; ``output`` is ``tmp_path/disk/run``."""
    for house in (dataset_copy / "artifacts").iterdir():
        f = house / f"{house.name}.json"
        f.write_text(f.read_text(encoding="utf-8").replace(" the ", " the é中😀 "), encoding="utf-8")
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(dataset_copy)}, "backend": {"name": "center"}, "strategy": "basic",
        "parser": "json", "scorers": ["official"], "runs": RUNS, "output": str(tmp_path / "disk" / "run"),
    }))  # fmt: skip
    (tmp_path / "disk").mkdir()
    return path


@pytest.fixture
def small_tmpfs(tmp_path):
    """``tmp_path/disk`` as a 64 KiB tmpfs; yields a function that grows it to 8 MiB."""
    disk = tmp_path / "disk"
    disk.mkdir(exist_ok=True)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"mounting a tmpfs is not permitted here ({mounted.stderr.strip()}); "
                    "test_a_file_size_limit_mid_run_... covers the same path with EFBIG")
    try:
        yield lambda: subprocess.run(["mount", "-o", "remount,size=8m", str(disk)], check=True)
    finally:
        subprocess.run(["umount", str(disk)], check=True)


def run(forks, pipeline: Path, limit_bytes: int | None = None) -> subprocess.CompletedProcess[str]:
    """``povagent run PIPELINE`` in a process of its own (tests/run/command_forks.py), under a
    file-size limit (RLIMIT_FSIZE) of ``limit_bytes`` if given."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return forks.run("run", pipeline, "--quiet", "--json", cwd=Path.cwd(), env=env, fsize=limit_bytes, timeout=150)


def complete_keys(results: Path) -> list[str]:
    return [json.loads(line)["key"] for line in results.read_bytes().splitlines(keepends=True) if line.endswith(b"\n")]


def assert_one_line_stop(done: subprocess.CompletedProcess[str], why: str, results: Path) -> int:
    assert done.returncode == 2, done.stderr[-3000:]
    assert "Traceback" not in done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and why in errors[0], done.stderr[-3000:]
    assert "run the same command again to resume" in errors[0]
    kept = complete_keys(results)  # every complete line is a row, each key once
    assert 0 < len(kept) == len(set(kept)) < KEYS
    return len(kept)


def resume_here(pipeline: Path) -> int:
    """The same pipeline run again in this process (after a stop, what the command does; an
    interpreter of its own costs a second of imports): its exit code."""
    from povagent.config.pipeline import load_pipeline
    from povagent.run.progress import QuietProgress
    from povagent.run.runner import run_pipeline

    return run_pipeline(load_pipeline(pipeline), progress=QuietProgress()).exit_code


def assert_resumed_exactly_once(done: subprocess.CompletedProcess[str] | int, results: Path) -> None:
    """``done``: the resuming command, or the exit code of :func:`resume_here`."""
    if isinstance(done, int):
        assert done == 0, f"the resume ended with exit code {done}"
        summary = json.loads((results.parent / "summary.json").read_text())
    else:
        assert done.returncode == 0, done.stderr[-3000:]
        summary = json.loads(done.stdout)
    keys = Counter(complete_keys(results))
    assert len(keys) == KEYS and max(keys.values()) == 1
    assert summary["complete"] is True and summary["rows"]["total"] == summary["rows"]["answered"] == KEYS
    assert results.read_bytes().endswith(b"\n")


def test_a_full_disk_mid_run_is_one_line_and_the_same_command_resumes(pipeline, small_tmpfs, tmp_path, command_forks):
    results = tmp_path / "disk" / "run" / "results.jsonl"
    assert_one_line_stop(run(command_forks, pipeline), "No space left on device", results)
    small_tmpfs()  # space is freed
    assert_resumed_exactly_once(resume_here(pipeline), results)


def test_a_file_size_limit_mid_run_is_one_line_and_the_same_command_resumes(pipeline, tmp_path, command_forks):
    results = tmp_path / "disk" / "run" / "results.jsonl"
    assert_one_line_stop(run(command_forks, pipeline, limit_bytes=48_000), "File too large", results)
    assert_resumed_exactly_once(resume_here(pipeline), results)


def test_a_tail_torn_inside_a_character_is_run_again_on_resume(pipeline, tmp_path, command_forks):
    results = tmp_path / "disk" / "run" / "results.jsonl"
    # the finished run to tear is made in this process; the resume below is the command's
    assert resume_here(pipeline) == 0 and len(complete_keys(results)) == KEYS
    data = results.read_bytes()
    last_start = data.rindex(b"\n", 0, len(data) - 1) + 1
    cut = data.index("😀".encode(), last_start) + 3  # inside the last row's emoji
    results.write_bytes(data[:cut])
    assert_resumed_exactly_once(run(command_forks, pipeline), results)
