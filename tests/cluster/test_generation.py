"""Houses made on a real Dask cluster are the houses one process makes, whatever goes wrong.

A scheduler and worker processes run on 127.0.0.1 (``conftest.start_cluster``); houses are tiny
(one exploration frame; two houses where the test needs two: houses spread over both workers, a
finished house beside an unfinished one; one house where a single house shows it: a killed worker,
a hidden folder, a lost scheduler) so the whole file stays within about a minute on an idle
machine. Every comparison is of the sha256 of every file against a one-process run. The tests share
one cluster (a worker killed by a test is replaced for the next one that asks): its workers start
and load the house pipeline once, not once per test. The worker is killed mid-house after the last
houses made on it, so its replacement never loads the pipeline again; the hidden-folder cluster,
its house pipeline loaded, is then the one whose scheduler is killed (``spare_cluster``).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from povagent.errors import ClusterError
from povagent.generate import generate_dataset

#: Seed 5's houses are among the cheapest to make of the seeds tried (house 0 about 1.1 s,
#: seed 21's 1.4 s) and have pairs in all four directions.
SEED, HOUSES, FRAMES = 5, 2, 1
#: Two tiny houses take seconds on an idle machine; a shared machine under load can take minutes.
pytestmark = pytest.mark.timeout(900)


def digests(root: Path) -> dict[str, str]:
    """sha256 of every file under ``root``, by relative path."""
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def one_process_folder(two_houses) -> Path:
    """The reference: the same houses made in one process, one after the other (the session's
    ``two_houses``, tests/conftest.py: made once a test run, whichever tests ask first)."""
    meta = json.loads((two_houses.root / "meta.json").read_text())
    assert (meta["seed"], meta["generator"]["frames"], meta["counts"]["houses"]) == (SEED, FRAMES, HOUSES), "two_houses' options changed"
    return two_houses.root


@pytest.fixture(scope="module")
def one_process(one_process_folder: Path) -> dict[str, str]:
    """The reference's digests (:func:`digests`)."""
    return digests(one_process_folder)


@pytest.fixture(scope="module")
def one_house(one_process_folder: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The one-house reference: a one-process run asked for one house over house 0 of the
    two-house reference, which it keeps (the houses do not depend on the count: it writes only
    ``meta.json``, and no house is made twice)."""
    out = tmp_path_factory.mktemp("one_house") / "data"
    (out / "artifacts").mkdir(parents=True)
    shutil.copytree(one_process_folder / "artifacts" / "train_house_00000", out / "artifacts" / "train_house_00000")
    report = generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, jobs=1, progress=False)
    assert (report.kept, report.generated) == (1, 0)
    return digests(out)


def _log_sizes(cluster: Any) -> dict[Path, int]:
    assert cluster.logs is not None
    return {p: p.stat().st_size for p in cluster.logs.glob("worker*.log")}


def _logs_since(cluster: Any, sizes: dict[Path, int]) -> str:
    """What the workers logged after ``sizes`` was taken (the cluster is shared by several tests)."""
    assert cluster.logs is not None
    return "".join(p.read_bytes()[sizes.get(p, 0):].decode(errors="replace") for p in sorted(cluster.logs.glob("worker*.log")))


def test_houses_made_on_the_cluster_equal_a_one_process_run(shared_dask_cluster, one_process, tmp_path) -> None:
    dask_cluster = shared_dask_cluster
    notices: list[str] = []
    seen: list[tuple[int, int]] = []
    out = tmp_path / "data"
    sizes = _log_sizes(dask_cluster)
    report = generate_dataset(out, houses=HOUSES, seed=SEED, frames=FRAMES, cluster=dask_cluster.address, notice=notices.append,
                              progress=lambda summary, done, total: seen.append((done, total)))
    assert digests(out) == one_process
    assert report.generated == HOUSES
    assert any(f"all 2 workers read and write {out}" in n for n in notices), notices
    # the progress callback counts houses as they finish on the cluster
    assert seen == [(1, HOUSES), (2, HOUSES)]
    # the workers' logs keep the structured format (files/logs.py's renderer: level, event, key=value)
    logs = _logs_since(dask_cluster, sizes)
    for index in range(HOUSES):
        assert re.search(rf"\[info\s*\] house done\s.*index={index} .*seed={SEED}", logs), logs[-2000:]


def test_workers_that_cannot_see_the_folder_send_the_houses_back(shared_hidden_cluster, one_house, tmp_path) -> None:
    assert shared_hidden_cluster.hidden is not None
    notices: list[str] = []
    out = shared_hidden_cluster.hidden / tmp_path.name / "data"  # where this process writes and the worker sees nothing
    generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False, cluster=shared_hidden_cluster.address, notice=notices.append)
    assert any(f"0 of 1 workers read and write {out}" in n for n in notices), notices
    assert digests(out) == one_house


def test_a_generation_whose_client_is_killed_half_way_resumes_to_the_same_bytes(shared_dask_cluster, one_process, tmp_path) -> None:
    dask_cluster = shared_dask_cluster
    out = tmp_path / "data"
    command = [sys.executable, "-c", "from povagent.cli import main; main()", "generate", "--out", str(out),
               "--houses", str(HOUSES), "--seed", str(SEED), "--frames", str(FRAMES), "--cluster", dask_cluster.address]
    client = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 180
        while not list(out.glob("artifacts/*/_generated.json")) and time.monotonic() < deadline and client.poll() is None:
            time.sleep(0.05)
        client.send_signal(signal.SIGKILL)
        client.wait(timeout=30)
    finally:
        if client.poll() is None:
            client.kill()
    first = sorted(out.glob("artifacts/*/_generated.json"))
    assert first and not (out / "meta.json").exists(), "the client was not stopped half way"
    report = generate_dataset(out, houses=HOUSES, seed=SEED, frames=FRAMES, progress=False, cluster=dask_cluster.address)
    assert report.kept >= len(first)
    assert digests(out) == one_process


def _started_on(cluster: Any, sizes: dict[Path, int]) -> set[int]:
    """The indices of the workers that logged ``house started`` since ``sizes`` was taken (each
    worker logs to ``worker<index>.log``, a replacement to ``worker<index>-<n>.log``)."""
    assert cluster.logs is not None
    found = set()
    for path in cluster.logs.glob("worker*.log"):
        if b"house started" in path.read_bytes()[sizes.get(path, 0) :]:
            name = re.fullmatch(r"worker(\d+)(-\d+)?\.log", path.name)
            assert name is not None, path
            found.add(int(name.group(1)))
    return found


def test_a_worker_killed_mid_house_still_gives_the_same_bytes(shared_dask_cluster, one_house, tmp_path) -> None:
    dask_cluster = shared_dask_cluster
    out = tmp_path / "data"
    sizes = _log_sizes(dask_cluster)
    killed: list[int] = []
    done = threading.Event()

    # One house: the worker rendering it (the one whose log says it started the house, once its
    # copy is staged) is killed, the other worker makes it again. The generation runs in this
    # process and the watcher reads the workers' logs, not the scheduler: a second Dask client
    # on another thread of one process trips over distributed's event loops (not what is tested)
    def kill_the_worker_mid_house() -> None:
        deadline = time.monotonic() + 300
        while not killed and not done.is_set() and time.monotonic() < deadline:
            started = _started_on(dask_cluster, sizes)
            if started and list(out.glob(".partial/train_house_*")):
                killed.append(dask_cluster.kill_worker(started.pop()))
            time.sleep(0.05)

    watcher = threading.Thread(target=kill_the_worker_mid_house, daemon=True)
    watcher.start()
    try:  # the next test to ask for the shared cluster gets a fresh worker in the victim's place
        report = generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False, cluster=dask_cluster.address)
    finally:
        done.set()
        watcher.join(timeout=60)
    assert killed, "no worker was seen rendering a house"
    assert _started_on(dask_cluster, sizes) == {0, 1}, "the other worker did not make the house again"
    assert report.generated == 1  # a failed house raises (the command would exit non-zero)
    assert digests(out) == one_house
    assert not (out / ".partial").exists()


def test_a_scheduler_gone_is_one_clear_line_and_the_same_command_resumes(spare_cluster, one_house, tmp_path) -> None:
    cluster = spare_cluster  # one worker; its scheduler is killed
    out = tmp_path / "data"

    def kill_the_scheduler_mid_house() -> None:
        deadline = time.monotonic() + 120
        while not list(out.glob(".partial/train_house_*")) and time.monotonic() < deadline:
            time.sleep(0.05)
        os.kill(cluster.scheduler.pid, signal.SIGKILL)

    threading.Thread(target=kill_the_scheduler_mid_house, daemon=True).start()
    with pytest.raises(ClusterError) as info:  # one house: the scheduler is killed while it is made
        generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False, cluster=cluster.address)

    message = str(info.value)
    assert "\n" not in message and cluster.address in message and "run the same command again to resume" in message
    # the files do not depend on the engine, so any engine resumes (here this process, to keep the test short)
    generate_dataset(out, houses=1, seed=SEED, frames=FRAMES, progress=False, jobs=1)
    assert digests(out) == one_house


@pytest.fixture
def full_disk(tmp_path: Path):
    """``tmp_path/disk``: a 64 KiB tmpfs filled to the last byte (unmounted after the test)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True, text=True)
    if mounted.returncode != 0:
        pytest.skip(f"mounting a tmpfs is not permitted here ({mounted.stderr.strip()})")
    try:
        (disk / "out").mkdir()
        try:
            with open(disk / "filler", "wb", buffering=0) as fh:
                while True:
                    fh.write(b"\0" * 4096)
        except OSError:  # the disk is full: what the test wants
            pass
        yield disk
    finally:
        subprocess.run(["umount", str(disk)], check=True)


def test_a_full_disk_under_a_cluster_generation_names_the_disk_not_the_scheduler(shared_dask_cluster, full_disk: Path) -> None:
    from povagent.errors import GenerationError

    # the module's running cluster (its workers see this disk): no LocalCluster to start
    with pytest.raises(GenerationError) as info:
        generate_dataset(full_disk / "out", houses=HOUSES, seed=SEED, frames=FRAMES, progress=False, cluster=shared_dask_cluster.address)
    message = str(info.value)
    assert "No space left on device" in message and "lost the Dask scheduler" not in message, message
    assert "\n" not in message and str(full_disk / "out") in message
