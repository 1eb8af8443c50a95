"""Only our own folders are written: a marker makes a run or sweep folder ours; someone's folder,
or one that cannot be written, is refused with one line before anything is written; folders of
earlier versions (no marker) still resume."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.run.run_folder import MARKER

pytestmark = pytest.mark.timeout(180)

THEIRS = {"config.yaml": "learning_rate: 0.1\nepochs: 3\n", "summary.json": '{"accuracy": 0.93}\n'}


def povagent(*args: str, cwd: Path, prefix: list[str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*(prefix or []), sys.executable, "-m", "povagent.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=150)


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


def test_a_folder_holding_someone_elses_files_is_refused_and_left_untouched(tmp_path, dataset_copy):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    for name, text in THEIRS.items():
        (theirs / name).write_text(text)
    before = snapshot(theirs)
    done = povagent("run", pipeline(tmp_path, dataset_copy, theirs), "--quiet", cwd=tmp_path)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and str(theirs) in lines[0] and "not a povagent run folder" in lines[0], done.stderr
    assert "choose another output folder" in lines[0] and "empty this one" in lines[0]
    assert snapshot(theirs) == before and sorted(p.name for p in theirs.iterdir()) == sorted(THEIRS)


def test_a_sweep_into_someone_elses_folder_is_refused_and_left_untouched(tmp_path, dataset_copy):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    for name, text in THEIRS.items():
        (theirs / name).write_text(text)
    before = snapshot(theirs)
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored")
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(theirs), "axes": {"backend": ["center", "random"]}}))
    done = povagent("sweep", sweep, "--quiet", cwd=tmp_path)
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


def test_a_run_folder_of_an_earlier_version_without_marker_resumes(tmp_path, dataset_copy):
    run = tmp_path / "run"
    run_here(pipeline(tmp_path, dataset_copy, run, instances={"limit": 5}))
    assert len(rows(run)) == 5
    (run / MARKER).unlink()  # what an earlier version left: the same files, no marker
    again = povagent("run", pipeline(tmp_path, dataset_copy, run), "--quiet", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    keys = rows(run)
    assert len(keys) == len(set(keys)) == 18  # every instance of the two houses, each once
    assert (run / MARKER).is_file()  # adopted


def test_a_sweep_folder_of_an_earlier_version_without_markers_resumes(tmp_path, dataset_copy):
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored", instances={"limit": 3})
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sw"), "axes": {"backend": ["center", "random"]}}))
    run_here(sweep)
    for marker in (tmp_path / "sw").rglob(MARKER):
        marker.unlink()
    before = {c: rows(tmp_path / "sw" / c) for c in ("center", "random")}
    done = povagent("sweep", sweep, "--quiet", cwd=tmp_path)
    assert done.returncode == 0, done.stdout + done.stderr
    assert {c: rows(tmp_path / "sw" / c) for c in ("center", "random")} == before
    assert (tmp_path / "sw" / MARKER).is_file() and (tmp_path / "sw" / "center" / MARKER).is_file()


def test_a_folder_with_results_that_are_not_ours_is_not_taken_for_an_earlier_run(tmp_path, dataset_copy):
    theirs = tmp_path / "experiment"
    theirs.mkdir()
    (theirs / "config.yaml").write_text(yaml.safe_dump({"dataset": str(dataset_copy), "backend": "center", "output": str(theirs)}))
    (theirs / "results.jsonl").write_text('{"epoch": 1, "loss": 0.5}\n')
    before = snapshot(theirs)
    done = povagent("run", pipeline(tmp_path, dataset_copy, theirs), "--quiet", cwd=tmp_path)
    assert done.returncode == 2 and "not a povagent run folder" in done.stderr, done.stderr
    assert snapshot(theirs) == before


# -- folders that cannot be written ---------------------------------------------------------------
def _read_only_mount(folder: Path) -> list[str]:
    """A command prefix that runs in a private mount namespace where ``folder`` is an empty
    read-only tmpfs (nothing outside the command sees the mount; it ends with the command)."""
    unshare = shutil.which("unshare")
    probe = subprocess.run([unshare or "unshare", "-rm", "true"], capture_output=True) if unshare else None
    if probe is None or probe.returncode != 0:
        pytest.skip("needs unshare -rm (user and mount namespaces) to mount a read-only tmpfs")
    folder.mkdir(parents=True, exist_ok=True)
    return ["unshare", "-rm", "sh", "-c", f'mount -t tmpfs -o ro,size=1m tmpfs "{folder}" && exec "$@"', "sh"]


@pytest.mark.parametrize("where", ["the folder itself", "a folder under it"])
def test_a_read_only_output_folder_is_one_line_not_a_traceback(tmp_path, dataset_copy, where):
    mount = tmp_path / "readonly"
    output = mount if where == "the folder itself" else mount / "runs" / "one"
    prefix = _read_only_mount(mount)
    done = povagent("run", pipeline(tmp_path, dataset_copy, output), "--quiet", cwd=tmp_path, prefix=prefix)
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith(f"error: {output}: cannot write the run folder") and "Read-only file system" in lines[0], lines[0]


def test_a_read_only_sweep_folder_is_one_line_not_a_traceback(tmp_path, dataset_copy):
    mount = tmp_path / "readonly"
    prefix = _read_only_mount(mount)
    pipeline(tmp_path, dataset_copy, tmp_path / "ignored")
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(mount / "sw"), "axes": {"backend": ["center"]}}))
    done = povagent("sweep", sweep, "--quiet", cwd=tmp_path, prefix=prefix)
    assert done.returncode == 2, done.stdout + done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and "cannot write the sweep folder" in done.stderr, done.stderr


def test_a_finished_run_on_a_folder_made_read_only_since_is_one_line(finished_run):
    path, run = finished_run
    unshare = shutil.which("unshare")
    if not unshare or subprocess.run([unshare, "-rm", "true"], capture_output=True).returncode != 0:
        pytest.skip("needs unshare -rm to remount the folder read-only")
    # the same folder, bind-mounted read-only over itself (in this command's namespace only)
    prefix = ["unshare", "-rm", "sh", "-c", f'mount --bind "{run}" "{run}" && mount -o remount,bind,ro "{run}" && exec "$@"', "sh"]
    before = snapshot(run)
    done = povagent("run", path, "--quiet", cwd=path.parent, prefix=prefix)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stdout + done.stderr
    assert "cannot write the run folder" in done.stderr
    assert snapshot(run) == before
