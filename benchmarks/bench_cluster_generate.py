"""Generation on a Dask cluster against ``--jobs``: throughput, engine cost, resume, extend.

Run: ``python benchmarks/bench_cluster_generate.py [--houses 6] [--frames 30] [--rounds 2]``
(needs the cluster extra). Everything is measured in one run, on this machine, rounds
interleaved (the machine is shared and noisy):

1. houses/minute: ``generate_dataset(jobs=2)`` against ``generate_dataset(cluster=client)`` on a
   ``LocalCluster`` of 2 single-threaded worker processes (started once, outside the timing; its
   start-up time is printed apart), the same houses, same seed; the bytes are compared.
2. the scheduler's cost per task: 2,000 no-op tasks through the same cluster; the worker-seconds
   each costs (wall x workers / tasks) against the CPU seconds of one house.
3. resume: ``povagent generate --cluster local:2`` killed with SIGKILL once half the houses are
   complete; the same command again; how many houses it re-rendered against how many were in
   flight (staged under ``.partial/``) when the client died; bytes compared with (1).
4. extend: the cost of the skip check per complete house (``generate_dataset`` over a finished
   dataset asking for the same houses: it reads every house's record twice and rewrites
   meta.json), scaled to 1,000 houses; so extending 1,000 -> 1,010 costs the 10 new houses plus
   that. Scaled from the measured houses, and said so.
5. houses/hour predicted at 16, 64 and 512 workers from the measured CPU seconds per house and
   the scheduler's cost per task (a single scheduler handles tasks one after another).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def digests(root: Path) -> dict[str, str]:
    return {p.relative_to(root).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(root.rglob("*")) if p.is_file()}


def _noop(i: int) -> int:
    return i


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--houses", type=int, default=6)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--noop-tasks", type=int, default=2000)
    args = parser.parse_args()

    import distributed

    from povagent.generate import generate_dataset

    tmp = Path(tempfile.mkdtemp(prefix="bench-cluster-"))
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; houses {args.houses}, frames {args.frames}, seed {args.seed}")
    try:
        started = time.perf_counter()
        local = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=50)
        client = distributed.Client(local)
        print(f"LocalCluster of 2 workers started in {time.perf_counter() - started:.1f} s (not counted below)")

        jobs_rate, cluster_rate, cpu_per_house = [], [], []
        reference = None
        for r in range(args.rounds):
            for engine in (("jobs", "cluster") if r % 2 == 0 else ("cluster", "jobs")):
                out = tmp / f"{engine}{r}"
                t = time.perf_counter()
                if engine == "jobs":
                    rep = generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames, jobs=2, progress=False)
                else:
                    rep = generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames, cluster=client, progress=False)
                wall = time.perf_counter() - t
                rate = 60 * args.houses / wall
                (jobs_rate if engine == "jobs" else cluster_rate).append(rate)
                cpu_per_house.append(rep.cpu_seconds / args.houses)
                d = digests(out)
                reference = reference or d
                print(f"round {r} {engine:7s}: {wall:6.1f} s, {rate:5.2f} houses/min, {rep.cpu_seconds / args.houses:.2f} CPU s/house, same bytes: {d == reference}")
        ratio = statistics.mean(c / j for c, j in zip(cluster_rate, jobs_rate))
        print(f"houses/minute: --jobs 2 {statistics.mean(jobs_rate):.2f}, LocalCluster(2) {statistics.mean(cluster_rate):.2f}; "
              f"cluster/jobs = {ratio:.3f}x (mean of per-round ratios; goal >= 0.95x)")
        house_cpu = statistics.median(cpu_per_house)
        house_bytes = sum(p.stat().st_size for p in (tmp / "jobs0" / "artifacts").rglob("*") if p.is_file()) / args.houses

        n = args.noop_tasks
        client.gather(client.map(_noop, range(50), pure=False))  # warm
        t = time.perf_counter()
        client.gather(client.map(_noop, range(n), pure=False))
        per_task = (time.perf_counter() - t) * 2 / n
        print(f"scheduler cost per task: {1000 * per_task:.2f} worker-ms ({n} no-op tasks, 2 workers) = "
              f"{100 * per_task / house_cpu:.3f}% of a house's {house_cpu:.2f} CPU s (goal < 2%)")
        client.close()
        local.close()

        # 3. resume after SIGKILL of the client at 50%
        out = tmp / "resume"
        half = args.houses // 2
        cmd = [sys.executable, "-c", "from povagent.cli import main; main()", "generate", "--out", str(out), "--houses", str(args.houses),
               "--seed", str(args.seed), "--frames", str(args.frames), "--cluster", "local:2"]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        deadline = time.monotonic() + 1800
        while len(list(out.glob("artifacts/*/_generated.json"))) < half and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.02)
        in_flight = sorted({p.name.split(".")[0] for p in out.glob(".partial/train_house_*")})
        complete = len(list(out.glob("artifacts/*/_generated.json")))
        os.killpg(proc.pid, signal.SIGKILL)  # the client and its LocalCluster's workers: everything on this machine
        proc.wait()
        time.sleep(1)
        t = time.perf_counter()
        rep = generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames, cluster="local:2", progress=False)
        print(f"resume: killed with {complete} of {args.houses} complete and {len(in_flight)} in flight {in_flight}; the re-run kept "
              f"{rep.kept}, rendered {rep.generated} ({args.houses - complete - len(in_flight)} never started) in "
              f"{time.perf_counter() - t:.1f} s; same bytes: {digests(out) == reference}")

        # 4. extend: the per-house cost of finding complete houses, on the real houses of (1)
        base = tmp / "jobs0"
        checks = []
        for _ in range(5):
            t = time.perf_counter()
            rep = generate_dataset(base, houses=args.houses, seed=args.seed, frames=args.frames, progress=False)
            checks.append(time.perf_counter() - t)
        assert rep.generated == 0
        per_house = statistics.median(checks) / args.houses
        print(f"skip check: {1000 * per_house:.2f} ms per complete house (median of 5 over {args.houses} real houses) -> "
              f"{1000 * per_house:.2f} s for 1,000 houses (scaled, not measured on 1,000); extend 1,000 -> 1,010 = "
              f"10 houses x {house_cpu:.1f} CPU s / workers + {1000 * per_house:.2f} s (goal < 5 s)")

        # 5. predicted houses/hour
        print(f"per house: {house_cpu:.2f} CPU s, {house_bytes / 1e6:.2f} MB written")
        for workers in (16, 64, 512):
            compute = workers * 3600 / house_cpu
            scheduler = 3600 / (per_task / 2)  # tasks the scheduler can hand out per hour, one at a time
            print(f"  {workers:4d} workers: {min(compute, scheduler):,.0f} houses/hour (workers alone {compute:,.0f}; "
                  f"scheduler bound, no-op tasks through one scheduler {scheduler:,.0f}); output {min(compute, scheduler) * house_bytes / 1e9:.1f} GB/hour")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
