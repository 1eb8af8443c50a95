"""Sweeps on a real Dask cluster give what one machine gives, survive a killed worker, report
failed cells and a lost scheduler, and leave Dask alone when no cluster is asked for."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.engine.cache import ResponseCache
from povagent.errors import ClusterError, ConfigError
from povagent.files.folder_lock import folder_lock
from povagent.run.progress import QuietProgress
from povagent.run.run_folder import claim_folder
from povagent.run.sweep import CELL_CACHE_SHARD, expand_sweep, run_sweep

#: What must be equal between a sweep on one machine and one on the cluster.
COMPARED = ("overall", "per_condition", "per_direction", "per_condition_direction", "rows", "official_parse")


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.exists() else []


def _keys(run_dir: Path) -> list[str]:
    return [json.loads(line)["key"] for line in _lines(run_dir / "results.jsonl")]


def _summaries(output: Path) -> dict[str, dict]:
    index = json.loads((output / "sweep.json").read_text())
    out = {}
    for cell in index["cells"]:
        summary = json.loads((Path(cell["run_dir"]) / "summary.json").read_text())
        out[cell["name"]] = {k: summary.get(k) for k in COMPARED}
    return out


def test_a_sweep_on_the_cluster_gives_the_summaries_of_one_machine(shared_dask_cluster, write_sweep, tmp_path) -> None:
    here = run_sweep(write_sweep(tmp_path / "here", runs=2), quiet=True)
    progress, said = QuietProgress(), []
    there = run_sweep(write_sweep(tmp_path / "there", runs=2), cluster=shared_dask_cluster.address, progress=progress, notify=said.append)
    assert not there.failed
    assert _summaries(tmp_path / "there") == _summaries(tmp_path / "here")
    assert [c.name for c in there.cells] == [c.name for c in here.cells] == ["a", "b", "c"]
    index = json.loads((tmp_path / "there" / "sweep.json").read_text())
    assert [c["status"] for c in index["cells"]] == ["done"] * 3
    # the bar counted every row of every cell, read from the journals the workers wrote
    assert sum(progress.counts.values()) == 3 * 4 * 2 == progress.counts["answered"]
    assert any(m.startswith("storage: all 2 worker(s) on 1 host(s) read and write") for m in said)
    # the answers reached the sweep's cache through the cells' shards, and no shard is left
    with ResponseCache(tmp_path / "here" / "cache.sqlite") as a, ResponseCache(tmp_path / "there" / "cache.sqlite") as b:
        assert len(b) == len(a) == 3 * 4 * 2
    assert not list((tmp_path / "there").glob(f"*/{CELL_CACHE_SHARD}"))
    # the worker's logs keep the structured format: JSON lines from run_start to run_end
    events = [json.loads(line)["event"] for line in _lines(tmp_path / "there" / "a" / "log.jsonl")]
    assert events[0] in ("run_start", "dataset_problem") and events[-1] == "run_end"


def test_rerunning_a_finished_cluster_sweep_asks_no_model(shared_dask_cluster, write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "again")
    run_sweep(path, cluster=shared_dask_cluster.address, progress=QuietProgress())
    for cell in expand_sweep(path)[1]:  # rows dropped: the keys run again, answered from the cache
        (Path(cell.config.output) / "results.jsonl").unlink()
    again = run_sweep(path, cluster=shared_dask_cluster.address, progress=QuietProgress())
    assert {name: (r.stats.requests, r.stats.cache_hits) for name, r in again.results.items()} == {n: (0, 4) for n in "abc"}


def test_the_flag_overrides_the_local_cluster_the_yaml_asks_for(shared_dask_cluster, write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "flagged", extra="cluster: local:1\n")
    result = CliRunner().invoke(app, ["sweep", str(path), "--quiet", "--cluster", shared_dask_cluster.address])
    assert result.exit_code == 0, result.output
    assert "storage: all 2 worker(s)" in result.output  # the running scheduler's two, not local:1's one


def test_a_yaml_naming_a_scheduler_is_refused_and_nothing_connects_to_it(write_sweep, tmp_path) -> None:
    # a hostile sweep file must not make povagent unpickle what some scheduler sends: the
    # address it names is refused before any connection, in one line naming --cluster
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(8)
        listener.setblocking(False)
        port = listener.getsockname()[1]
        path = write_sweep(tmp_path / "hostile", extra=f"cluster: tcp://127.0.0.1:{port}\n")
        with pytest.raises(ConfigError) as info:
            run_sweep(path, progress=QuietProgress())
        with pytest.raises(BlockingIOError):
            listener.accept()  # nobody knocked
    message = str(info.value)
    assert "hostile.yaml, line 5" in message and "--cluster" in message and "local:N only" in message, message
    assert not (tmp_path / "hostile").exists()  # refused before the sweep folder was made


def test_a_bad_cluster_key_names_the_sweep_file_and_line(write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "bad", extra="cluster: local:zero\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml, line 5: .*local:N takes a number of worker processes"):
        expand_sweep(path)


def test_images_served_over_http_are_refused_before_any_cluster_starts(write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "http", base_extra={"images": {"transport": "http", "bind": "127.0.0.1:0"}})
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match=r"cell a: images.transport: http serves images from one port of one process"):
        run_sweep(path, cluster="local:2", progress=QuietProgress())
    assert time.monotonic() - t0 < 5  # refused before a LocalCluster could start


def test_a_failing_cell_is_reported_and_the_others_finish(shared_dask_cluster, write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "failing")
    held = tmp_path / "failing" / "b"
    claim_folder(tmp_path / "failing", "sweep")  # the sweep's folders, marked as povagent's own
    claim_folder(held, "run")
    with folder_lock(held):  # another process runs cell b: its task raises, twice (one retry)
        result = CliRunner().invoke(app, ["sweep", str(path), "--quiet", "--cluster", shared_dask_cluster.address])
    assert result.exit_code == 4, result.output
    assert "cell b failed: ConfigError:" in result.output and "another povagent process is running" in result.output
    assert f"run `povagent sweep {path} --cluster {shared_dask_cluster.address}` again to resume" in result.output.replace("\n", "")
    index = {c["name"]: c for c in json.loads((tmp_path / "failing" / "sweep.json").read_text())["cells"]}
    assert (index["a"]["status"], index["b"]["status"], index["c"]["status"]) == ("done", "failed", "done")
    assert "ConfigError" in index["b"]["error"]
    assert len(_keys(tmp_path / "failing" / "a")) == len(_keys(tmp_path / "failing" / "c")) == 4
    # the lock released, the same command finishes cell b alone
    again = run_sweep(path, cluster=shared_dask_cluster.address, progress=QuietProgress())
    assert not again.failed and {n: r.stats.requests for n, r in again.results.items()} == {"a": 0, "b": 4, "c": 0}


def _start_in_thread(path: Path, cluster: str) -> tuple[threading.Thread, dict]:
    outcome: dict = {}

    def go() -> None:
        try:
            outcome["result"] = run_sweep(path, cluster=cluster, progress=QuietProgress())
        except BaseException as exc:  # handed to the test
            outcome["error"] = exc

    thread = threading.Thread(target=go, daemon=True)
    thread.start()
    return thread, outcome


def _wait_for_rows(folders: list[Path], at_least: int, thread: threading.Thread, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while not all(len(_lines(f / "results.jsonl")) >= at_least for f in folders):
        assert thread.is_alive(), "the sweep ended before the kill"
        assert time.monotonic() < deadline, "no rows in time"
        time.sleep(0.02)


def test_a_lost_scheduler_is_said_in_one_line_and_the_same_command_resumes(spare_cluster, shared_dask_cluster, write_sweep, tmp_path) -> None:
    path = write_sweep(tmp_path / "orphan", delay_s=0.04, runs=6, concurrency=1, axes="conditions: [a, b]")
    # one worker (a start less): cell a is under way when the scheduler goes, cell b waits for it
    cluster = spare_cluster
    thread, outcome = _start_in_thread(path, cluster.address)
    _wait_for_rows([tmp_path / "orphan" / "a"], 3, thread)
    cluster.scheduler.kill()  # the scheduler gone mid-sweep (SIGKILL) ...
    cluster.scheduler.wait(timeout=30)
    cluster.kill_worker(0)  # ... and its worker: it is not left finishing a cell on its own
    thread.join(timeout=60)
    assert not thread.is_alive()
    error = outcome.get("error")
    assert isinstance(error, ClusterError), error
    assert "went away" in str(error) and "run the same command to resume" in str(error) and "\n" not in str(error)
    index = json.loads((tmp_path / "orphan" / "sweep.json").read_text())
    assert {c["status"] for c in index["cells"]} <= {"interrupted", "done"}
    kept = len(_lines(tmp_path / "orphan" / "a" / "results.jsonl"))
    assert kept >= 3
    again = run_sweep(path, cluster=shared_dask_cluster.address, progress=QuietProgress())  # another scheduler
    assert not again.failed
    for name in "ab":
        keys = _keys(tmp_path / "orphan" / name)
        assert len(keys) == len(set(keys)) == 24


def test_a_worker_killed_mid_cell_loses_and_duplicates_nothing(shared_dask_cluster, write_sweep, tmp_path) -> None:
    dask_cluster = shared_dask_cluster
    # the file's last test on the shared cluster: no worker is started in the killed one's place
    # two cells of 4 instances x 6 runs, one request at a time (40 ms): each worker holds a cell
    slow = {"delay_s": 0.04, "runs": 6, "concurrency": 1, "axes": "conditions: [a, b]"}
    path = write_sweep(tmp_path / "killed", **slow)
    thread, outcome = _start_in_thread(path, dask_cluster.address)
    cells = [tmp_path / "killed" / "a", tmp_path / "killed" / "b"]
    _wait_for_rows(cells, 3, thread)
    before = {c.name: _lines(c / "results.jsonl") for c in cells}
    dask_cluster.kill_worker(0)  # the next test to ask for the shared cluster gets a fresh one
    thread.join(timeout=120)
    assert not thread.is_alive() and "error" not in outcome, outcome.get("error")
    assert not outcome["result"].failed
    for cell in cells:
        keys = _keys(cell)
        assert len(keys) == len(set(keys)) == 4 * 6, cell.name
        complete_before = [line for line in before[cell.name] if line.endswith("}")]
        assert _lines(cell / "results.jsonl")[: len(complete_before) - 1] == complete_before[:-1]  # rows before the kill kept
    # one cell was cut short on the killed worker and resumed on the other
    assert any(0 < len(b) < 24 for b in before.values())
    here = run_sweep(write_sweep(tmp_path / "here", **slow | {"delay_s": 0.0}), quiet=True)
    assert not here.failed
    assert _summaries(tmp_path / "killed") == _summaries(tmp_path / "here")


#: What the child below says on stderr between the two commands.
_GENERATED = "-- generate done --"


def test_a_sweep_or_a_generation_without_a_cluster_never_imports_dask(write_sweep, tmp_path) -> None:
    # one child runs both commands (one interpreter start rather than two): `generate` (one
    # house, so in the child itself whatever --jobs says: what is read is the child's imports),
    # then `sweep`; the console script ends sweep with os._exit, so what each imported is read
    # from -X importtime's log, split at a line the child prints between them. Seed 5's first
    # house costs less than half of seed 0's (1.1 s against 2.7 s)
    path, data = write_sweep(tmp_path / "plain"), tmp_path / "data"
    code = (
        "import sys; from povagent.cli import main\n"
        f"sys.argv = ['povagent', 'generate', '--out', {str(data)!r}, '--houses', '1', '--seed', '5', '--frames', '1', '--jobs', '2']\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    assert not exc.code, exc.code\n"
        f"print({_GENERATED!r}, file=sys.stderr, flush=True)\n"
        f"sys.argv = ['povagent', 'sweep', {str(path)!r}, '--quiet']\nmain()\n"
    )
    out = subprocess.run([sys.executable, "-X", "importtime", "-c", code], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert _GENERATED in out.stderr.splitlines(), out.stderr[-2000:]
    generate_log, sweep_log = out.stderr.split(_GENERATED, 1)

    def imported(log: str) -> set[str]:
        return {line.rsplit("|", 1)[-1].strip() for line in log.splitlines() if line.startswith("import time:")}

    assert "povagent.generate.house_task" in imported(generate_log) and "povagent.run.sweep" in imported(sweep_log)  # the log is read right
    assert not {m for m in imported(generate_log) if m.split(".")[0] in ("dask", "distributed")}, "generate without --cluster imported Dask"
    assert not {m for m in imported(sweep_log) if m.split(".")[0] in ("dask", "distributed")}, "sweep without --cluster imported Dask"
    assert (data / "meta.json").exists(), "the generation did not finish"
    assert len(_keys(tmp_path / "plain" / "a")) == 4, "the sweep did not finish"
