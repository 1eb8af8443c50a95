"""Only our own folders are written: a marker makes a run or sweep folder ours; someone's folder,
or one that cannot be written, is refused with one line before anything is written; folders of
earlier versions (no marker) still resume."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from povagent.run.run_folder import MARKER

pytestmark = pytest.mark.timeout(180)

THEIRS = {"config.yaml": "learning_rate: 0.1\nepochs: 3\n", "summary.json": '{"accuracy": 0.93}\n'}


def povagent(forks, *args: object, cwd: Path, before: list[str] | None = None) -> subprocess.CompletedProcess[str]:
    """``povagent ARGS`` in a process of its own (tests/run/command_forks.py), after the shell
    commands ``before`` ran in that process."""
    return forks.run(*args, cwd=cwd, before=before, timeout=150)


def pipeline(tmp_path: Path, dataset: Path, output: Path, **keys) -> Path:
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({"dataset": str(dataset), "backend": "center", "cache": False, "output": str(output), **keys}))
    return path


def run_here(path: Path) -> None:
    """A run or sweep that only prepares a folder for the command under test, made in this
    process (an interpreter of its own costs a second of imports and tests nothing more here)."""
    from povagent.config.pipeline import load_pipeline
    from povagent.run.progress import QuietProgress
    from povagent.run.runner import run_pipeline
    from povagent.run.sweep import run_sweep

    if yaml.safe_load(path.read_text()).get("axes"):
        assert all(r.exit_code == 0 for r in run_sweep(path, quiet=True).results.values())
    else:
        assert run_pipeline(load_pipeline(path), progress=QuietProgress()).exit_code == 0


def snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def rows(run: Path) -> list[str]:
    return [json.loads(line)["key"] for line in (run / "results.jsonl").read_text().splitlines()]


def test_a_folder_holding_someone_elses_files_is_refused_and_left_untouched(tmp_path, dataset_copy, command_forks):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    for name, text in THEIRS.items():
        (theirs / name).write_text(text)
    before = snapshot(theirs)
    done = povagent(command_forks, "run", pipeline(tmp_path, dataset_copy, theirs), "--quiet", cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and str(theirs) in lines[0] and "not a povagent run folder" in lines[0], done.stderr
    assert "choose another output folder" in lines[0] and "empty this one" in lines[0]
    assert snapshot(theirs) == before and sorted(p.name for p in theirs.iterdir()) == sorted(THEIRS)


def test_a_sweep_into_someone_elses_folder_is_refused_and_left_untouched(tmp_path, dataset_copy, command_forks):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    for name, text in THEIRS.items():
        (theirs / name).write_text(text)
    before = snapshot(theirs)
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored")
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(theirs), "axes": {"backend": ["center", "random"]}}))
    done = povagent(command_forks, "sweep", sweep, "--quiet", cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    assert "not a povagent sweep folder" in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert snapshot(theirs) == before and sorted(p.name for p in theirs.iterdir()) == sorted(THEIRS)


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory, mini_root) -> tuple[Path, Path]:
    """(pipeline, run folder): a run of two instances over a copy of the fixture's two good houses,
    made in a folder that was empty, finished once for the module's tests that only read it."""
    home = tmp_path_factory.mktemp("finished")
    dataset = home / "ds"
    (dataset / "artifacts").mkdir(parents=True)
    shutil.copy(mini_root / "meta.json", dataset / "meta.json")
    for house in ("train_house_00000", "train_house_00001"):
        shutil.copytree(mini_root / "artifacts" / house, dataset / "artifacts" / house)
    empty = home / "empty"
    empty.mkdir()
    path = pipeline(home, dataset, empty, instances={"limit": 2})
    run_here(path)
    return path, empty


def test_a_new_run_folder_carries_the_marker_and_an_empty_folder_is_taken(finished_run):
    _, empty = finished_run
    assert json.loads((empty / MARKER).read_text()) == {"format": 1, "kind": "run"}


def test_a_run_folder_of_an_earlier_version_without_marker_resumes(tmp_path, dataset_copy, command_forks):
    run = tmp_path / "run"
    run_here(pipeline(tmp_path, dataset_copy, run, instances={"limit": 5}))
    assert len(rows(run)) == 5
    (run / MARKER).unlink()  # what an earlier version left: the same files, no marker
    again = povagent(command_forks, "run", pipeline(tmp_path, dataset_copy, run), "--quiet", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    keys = rows(run)
    assert len(keys) == len(set(keys)) == 18  # every instance of the two houses, each once
    assert (run / MARKER).is_file()  # adopted


def test_a_sweep_folder_of_an_earlier_version_without_markers_resumes(tmp_path, dataset_copy, command_forks):
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored", instances={"limit": 3})
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sw"), "axes": {"backend": ["center", "random"]}}))
    run_here(sweep)
    for marker in (tmp_path / "sw").rglob(MARKER):
        marker.unlink()
    before = {c: rows(tmp_path / "sw" / c) for c in ("center", "random")}
    done = povagent(command_forks, "sweep", sweep, "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert {c: rows(tmp_path / "sw" / c) for c in ("center", "random")} == before
    assert (tmp_path / "sw" / MARKER).is_file() and (tmp_path / "sw" / "center" / MARKER).is_file()


def test_a_folder_with_results_that_are_not_ours_is_not_taken_for_an_earlier_run(tmp_path, dataset_copy, command_forks):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    (theirs / "config.yaml").write_text(yaml.safe_dump({"dataset": str(dataset_copy), "backend": "center", "output": str(theirs)}))
    (theirs / "results.jsonl").write_text('{"epoch": 1, "loss": 0.5}\n')
    before = snapshot(theirs)
    done = povagent(command_forks, "run", pipeline(tmp_path, dataset_copy, theirs), "--quiet", cwd=tmp_path)
    assert done.returncode == 2 and "not a povagent run folder" in done.stderr, done.stderr
    assert snapshot(theirs) == before


# -- folders that cannot be written ---------------------------------------------------------------
@pytest.fixture(scope="module")
def namespaced_forks(tmp_path_factory):
    """Commands as processes of their own (tests/run/command_forks.py) in a private user and
    mount namespace (``unshare -rm``): a mount one of them makes there is seen by no process
    outside it, and ends with the namespace when the module's tests are done. Each mount is of
    a folder of its test's own."""
    from command_forks import CommandForks

    unshare = shutil.which("unshare")
    if not unshare or subprocess.run([unshare, "-rm", "true"], capture_output=True).returncode != 0:
        pytest.skip("needs unshare -rm (user and mount namespaces) to mount a folder read-only")
    forks = CommandForks(tmp_path_factory.mktemp("namespaced-forks"), dict(os.environ), prefix=[unshare, "-rm"])
    try:
        yield forks
    finally:
        forks.close()


def _read_only_mount(folder: Path) -> list[str]:
    """The shell command that makes ``folder`` an empty read-only tmpfs (in the namespace)."""
    folder.mkdir(parents=True, exist_ok=True)
    return [f'mount -t tmpfs -o ro,size=1m tmpfs "{folder}"']


@pytest.mark.parametrize("where", ["the folder itself", "a folder under it"])
def test_a_read_only_output_folder_is_one_line_not_a_traceback(tmp_path, dataset_copy, where, namespaced_forks):
    mount = tmp_path / "readonly"
    output = mount if where == "the folder itself" else mount / "runs" / "one"
    before = _read_only_mount(mount)
    done = povagent(namespaced_forks, "run", pipeline(tmp_path, dataset_copy, output), "--quiet", cwd=tmp_path, before=before)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith(f"error: {output}: cannot write the run folder") and "Read-only file system" in lines[0], lines[0]


def test_a_read_only_sweep_folder_is_one_line_not_a_traceback(tmp_path, dataset_copy, namespaced_forks):
    mount = tmp_path / "readonly"
    before = _read_only_mount(mount)
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored")
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(mount / "sw"), "axes": {"backend": ["center"]}}))
    done = povagent(namespaced_forks, "sweep", sweep, "--quiet", cwd=tmp_path, before=before)
    assert done.returncode == 2, done.stdout + done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "cannot write the sweep folder" in done.stderr, done.stderr


def test_a_finished_run_on_a_folder_made_read_only_since_is_one_line(finished_run, namespaced_forks):
    path, run = finished_run
    # the same folder, bind-mounted read-only over itself (in the namespace only)
    mount = [f'mount --bind "{run}" "{run}" && mount -o remount,bind,ro "{run}"']
    before = snapshot(run)
    done = povagent(namespaced_forks, "run", path, "--quiet", cwd=path.parent, before=mount)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stdout + done.stderr
    assert "cannot write the run folder" in done.stderr
    assert snapshot(run) == before
