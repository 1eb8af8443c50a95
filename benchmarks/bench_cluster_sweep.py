"""A sweep on a Dask LocalCluster of 2 workers against the same sweep on one machine.

    python benchmarks/bench_cluster_sweep.py [--data FOLDER] [--rounds 3] [--latency 0.1] [--cells 12]

The model is the loopback OpenAI-compatible server (``povagent.testing.loopback_server``, in its
own process, refusing any image that is not one of the dataset's frames) answering every
request after ``--latency`` seconds, reached through the real ``litellm``
backend; the data is a dataset made by ``povagent generate`` (``--data``, or 4 houses of 30
frames generated first: rendered 512x512 PNGs, each request carrying a house's 30 frames
inline), each cell its first 24 instances of one condition; the sweep is conditions a/b/c x
``cells / 3`` run indices, each cell at
``--concurrency`` (2: the model's latency, not this 2-core machine's CPU, bounds a cell, as it
does against a real model server), response cache off (every round really asks the server).

Printed, per round (the two modes interleaved, their order alternating):

* rows/s of each mode, and their ratio in that round (the figure to quote: a sweep is bound by
  the model's latency, so two workers running two cells at once should come near 2x);
* the scheduling cost per cell: a sweep of ``--cells`` trivial cells (the offline ``center``
  baseline, one instance each) in each mode; ``(cluster wall x 2 workers - one-machine wall) /
  cells`` is the worker time the engine adds to a cell: submitting and pickling the task, the
  storage probe, the client's planning, the worker's start of the cell, collecting the result.

The LocalCluster is started once (its start time is printed) and warmed by one sweep that is
not counted (each worker imports litellm once, seconds).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import yaml
from generated_frames import frame_digests, generated_dataset, start_verifying_server, stop_verifying_server

from povagent.run.progress import QuietProgress
from povagent.run.sweep import run_sweep

#: Instances of a cell (each cell is one condition).
INSTANCES_PER_CELL = 24


def write_sweep(folder: Path, release: Path, url: str | None, cells: int, output: Path, concurrency: int = 2) -> Path:
    """A sweep YAML of ``cells`` cells (3 conditions x cells/3 runs) against ``url`` (``None``:
    trivial cells, the offline ``center`` baseline over one instance)."""
    base: dict = {
        "dataset": {"path": str(release)},
        "backend": {"name": "litellm", "options": {"model": "openai/bench-model", "api_base": url, "api_key_env": "BENCH_KEY"}},
        "strategy": "basic",
        "parser": "json",
        "concurrency": concurrency,
        "cache": False,
        "output": "ignored",
        "instances": {"limit": INSTANCES_PER_CELL},
    }
    if url is None:
        base.update(backend={"name": "center"}, instances={"limit": 1})
    (folder / f"base-{output.name}.yaml").write_text(yaml.safe_dump(base))
    runs = list(range(max(1, cells // 3)))
    path = folder / f"sweep-{output.name}.yaml"
    path.write_text(yaml.safe_dump({"base": f"base-{output.name}.yaml", "output": str(output), "cache": False,
                                    "axes": {"conditions": ["a", "b", "c"], "runs": runs}}))
    return path


def measure(path: Path, cluster: object | None) -> tuple[float, int]:
    """``(wall s, rows)`` of one sweep."""
    t0 = time.perf_counter()
    result = run_sweep(path, cluster=cluster, quiet=True, progress=QuietProgress())
    wall = time.perf_counter() - t0
    assert not result.failed, result.failed
    return wall, sum(r.summary.rows.done for r in result.results.values())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate 4 houses)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--latency", type=float, default=0.1, help="seconds the server takes per answer")
    ap.add_argument("--cells", type=int, default=12, help="cells of the sweep (a multiple of 3)")
    ap.add_argument("--concurrency", type=int, default=2, help="requests in flight per cell")
    args = ap.parse_args()

    from distributed import Client, LocalCluster

    os.environ["BENCH_KEY"] = "bench-key"  # the workers inherit it (litellm wants a key)
    tmp = Path(tempfile.mkdtemp(prefix="bench-cluster-sweep-"))
    try:
        release = generated_dataset(args.data, tmp, houses=4)
        frame_digests(release, tmp / "frames.sha256")
        # the server in its own process (the one-machine sweep shares none of its CPU), checking
        # every image it receives against the dataset's frames
        proc, server_url = start_verifying_server(tmp / "frames.sha256", lifetime_s=3600, delay_s=args.latency,
                                           reply='{"selected_image": 0, "x": 255, "y": 255}')
        try:
            t0 = time.perf_counter()
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                              silence_logs=50) as local, Client(local) as client:
                started = time.perf_counter() - t0
                measure(write_sweep(tmp, release, server_url, args.cells, tmp / "warm", args.concurrency), client)
                print(f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}; data {release}; "
                      f"LocalCluster of 2 workers started in {started:.1f} s; {args.cells} cells, server latency "
                      f"{args.latency:g} s, concurrency {args.concurrency} per cell")
                print(f"{'round':>5} {'one machine rows/s':>19} {'cluster rows/s':>15} {'ratio':>6} "
                      f"{'trivial cell here':>18} {'trivial cell cluster':>21} {'engine cost/cell':>17}")
                ratios, costs = [], []
                for r in range(args.rounds):
                    out: dict[str, tuple[float, int]] = {}
                    for mode in (("here", "cluster") if r % 2 == 0 else ("cluster", "here")):
                        for kind, url in (("rows", server_url), ("trivial", None)):
                            output = tmp / f"{mode}-{kind}{r}"
                            path = write_sweep(tmp, release, url, args.cells, output, args.concurrency)
                            out[f"{mode}-{kind}"] = measure(path, client if mode == "cluster" else None)
                            shutil.rmtree(output)
                    rate = {m: out[f"{m}-rows"][1] / out[f"{m}-rows"][0] for m in ("here", "cluster")}
                    ratios.append(rate["cluster"] / rate["here"])
                    per = {m: out[f"{m}-trivial"][0] / args.cells for m in ("here", "cluster")}
                    costs.append(2 * per["cluster"] - per["here"])
                    print(f"{r:>5} {rate['here']:>19.1f} {rate['cluster']:>15.1f} {ratios[-1]:>5.2f}x "
                          f"{1000 * per['here']:>15.0f} ms {1000 * per['cluster']:>18.0f} ms {1000 * costs[-1]:>14.0f} ms")
                print(f"{out['here-rows'][1]} rows a sweep; median ratio cluster/one machine {statistics.median(ratios):.2f}x; "
                      f"median engine cost per cell {1000 * statistics.median(costs):.0f} ms of worker time; "
                      f"load average {os.getloadavg()[0]:.1f}")
        finally:
            checked = stop_verifying_server(proc)
            print(f"server: {checked.get('requests')} requests, {checked.get('images_fetched')} images checked against the "
                  f"dataset's SHA-256s, {checked.get('image_failures')} refused")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
