"""Generation on a Dask cluster against ``--jobs``: throughput, engine cost, resume, extend.

Run: ``python benchmarks/bench_cluster_generate.py [--houses 6] [--frames 30] [--rounds 2]``
(needs the cluster extra). Everything is measured in one run, on this machine, rounds
interleaved (the machine is shared and noisy):

1. houses/minute: ``generate_dataset(jobs=2)`` against ``generate_dataset(cluster=client)`` on a
   ``LocalCluster`` of 2 single-threaded worker processes (started once, outside the timing; its
   start-up time is printed apart), the same houses, same seed; the bytes are compared. Beside
   the wall-clock rate, the CPU of the whole process tree (this process with the LocalCluster's
   scheduler, the pool's or the cluster's worker processes and the nannies) per house: on a
   shared machine the wall clock measures the neighbours' load as much as the engine, while the
   CPU each mode spends on the same houses is what the engine costs.
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


def _cpu() -> float:
    return time.process_time()


def tree_cpu() -> float:
    """CPU seconds (user + system) of this process, its reaped children and every live descendant.

    A process pool's workers are reaped when the pool shuts down (their time lands in
    ``RUSAGE_CHILDREN``); a LocalCluster's nannies and workers stay alive (read through psutil,
    which distributed already needs)."""
    import resource

    import psutil

    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    total = time.process_time() + children.ru_utime + children.ru_stime
    for proc in psutil.Process().children(recursive=True):
        try:
            t = proc.cpu_times()
        except psutil.NoSuchProcess:
            continue
        total += t.user + t.system
    return total


def scheduler_cost(client, n: int, house_cpu: float) -> tuple[float, float]:
    """CPU seconds per task: this process (client + the LocalCluster's scheduler) and the workers."""
    client.gather(client.map(_noop, range(50), pure=False))  # warm
    workers_before = client.run(_cpu)
    here = time.process_time()
    t = time.perf_counter()
    client.gather(client.map(_noop, range(n), pure=False))
    wall = time.perf_counter() - t
    scheduler_cpu = (time.process_time() - here) / n
    workers_after = client.run(_cpu)
    worker_cpu = sum(workers_after[w] - workers_before[w] for w in workers_after) / n
    per_task = scheduler_cpu + worker_cpu
    print(f"scheduler cost per task ({n} no-op tasks, 2 workers): {1000 * scheduler_cpu:.2f} ms CPU client+scheduler, "
          f"{1000 * worker_cpu:.2f} ms CPU on workers, {1000 * wall / n:.2f} ms wall each; "
          f"{100 * per_task / house_cpu:.3f}% of a house's {house_cpu:.2f} CPU s (goal < 2%)")
    return per_task, scheduler_cpu


def extend_cost(base: Path, houses: int, seed: int, frames: int, house_cpu: float) -> None:
    """What extending a dataset costs beyond its new houses: a fixed part and a part per complete house."""
    from povagent.generate import generate_dataset
    from povagent.generate.record import complete_houses

    fixed_and_scan = []
    for _ in range(5):
        t = time.perf_counter()
        rep = generate_dataset(base, houses=houses, seed=seed, frames=frames, progress=False)
        fixed_and_scan.append(time.perf_counter() - t)
        assert rep.generated == 0
    scans = []
    for _ in range(50):
        t = time.perf_counter()
        complete_houses(base)
        scans.append(time.perf_counter() - t)
    per_house = statistics.median(scans) / houses
    whole = statistics.median(fixed_and_scan)
    fixed = whole - 2 * houses * per_house  # generate_dataset reads the records twice: to skip, and for meta.json
    extra = fixed + 2 * 1000 * per_house
    print(f"skip check: a re-run over {houses} complete houses takes {whole:.3f} s (median of 5): {fixed:.3f} s fixed "
          f"(judge and plugins, meta.json) + 2 x {1000 * per_house:.3f} ms per house (median of 50 scans of the records). "
          f"Scaled to 1,000 houses (not measured on 1,000): {extra:.2f} s, so extending 1,000 -> 1,010 = the 10 new houses "
          f"({10 * house_cpu:.0f} CPU s over the workers) + {extra:.2f} s (goal < 5 s)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--houses", type=int, default=6)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--noop-tasks", type=int, default=2000)
    parser.add_argument("--only-scheduler", type=float, metavar="HOUSE_CPU_S", default=None,
                        help="measure only the scheduler's cost per task, against a house of this many CPU seconds")
    parser.add_argument("--only-extend", type=Path, metavar="DATASET", default=None,
                        help="measure only the extend overhead, on a dataset this generator made")
    parser.add_argument("--house-cpu", type=float, default=8.25, help="CPU seconds of a house, for --only-extend's sum")
    args = parser.parse_args()
    if args.only_extend is not None:
        from povagent.generate.record import complete_houses

        found = complete_houses(args.only_extend)
        any_record = next(iter(found.values()))
        print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; {len(found)} houses in {args.only_extend}")
        extend_cost(args.only_extend, len(found), any_record.options["seed"], any_record.options["frames"], args.house_cpu)
        return
    if args.only_scheduler is not None:
        import distributed

        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=50) as local, \
                distributed.Client(local) as client:
            print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
            scheduler_cost(client, args.noop_tasks, args.only_scheduler)
        return

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
        jobs_tree, cluster_tree = [], []
        reference = None
        for r in range(args.rounds):
            for engine in (("jobs", "cluster") if r % 2 == 0 else ("cluster", "jobs")):
                out = tmp / f"{engine}{r}"
                tree_before = tree_cpu()
                t = time.perf_counter()
                if engine == "jobs":
                    rep = generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames, jobs=2, progress=False)
                else:
                    rep = generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames, cluster=client, progress=False)
                wall = time.perf_counter() - t
                tree = (tree_cpu() - tree_before) / args.houses
                rate = 60 * args.houses / wall
                (jobs_rate if engine == "jobs" else cluster_rate).append(rate)
                (jobs_tree if engine == "jobs" else cluster_tree).append(tree)
                cpu_per_house.append(rep.cpu_seconds / args.houses)
                d = digests(out)
                reference = reference or d
                print(f"round {r} {engine:7s}: {wall:6.1f} s, {rate:5.2f} houses/min, {rep.cpu_seconds / args.houses:.2f} CPU s/house "
                      f"in the houses, {tree:.2f} CPU s/house in all processes, load {os.getloadavg()[0]:.1f}, same bytes: {d == reference}")
        ratio = statistics.mean(c / j for c, j in zip(cluster_rate, jobs_rate))
        print(f"houses/minute: --jobs 2 {statistics.mean(jobs_rate):.2f}, LocalCluster(2) {statistics.mean(cluster_rate):.2f}; "
              f"cluster/jobs = {ratio:.3f}x (mean of per-round ratios, rounds "
              f"{min(c / j for c, j in zip(cluster_rate, jobs_rate)):.2f}-{max(c / j for c, j in zip(cluster_rate, jobs_rate)):.2f}x; goal >= 0.95x)")
        cpu_ratio = statistics.median(j / c for c, j in zip(cluster_tree, jobs_tree))
        print(f"houses per CPU-second, every process counted: --jobs 2 {1 / statistics.median(jobs_tree):.4f}, LocalCluster(2) "
              f"{1 / statistics.median(cluster_tree):.4f}; cluster/jobs = {cpu_ratio:.3f}x (median of per-round ratios; the engine's "
              f"CPU share: {100 * (1 - cpu_ratio):+.1f}% against the process pool)")
        house_cpu = statistics.median(cpu_per_house)
        house_bytes = sum(p.stat().st_size for p in (tmp / "jobs0" / "artifacts").rglob("*") if p.is_file()) / args.houses

        _, scheduler_cpu = scheduler_cost(client, args.noop_tasks, house_cpu)
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
        extend_cost(tmp / "jobs0", args.houses, args.seed, args.frames, house_cpu)

        # 5. predicted houses/hour
        print(f"per house: {house_cpu:.2f} CPU s, {house_bytes / 1e6:.2f} MB written")
        for workers in (16, 64, 512):
            compute = workers * 3600 / house_cpu
            scheduler = 3600 / scheduler_cpu  # tasks one scheduler can hand out per hour at its measured CPU per task
            print(f"  {workers:4d} workers: {min(compute, scheduler):,.0f} houses/hour (workers alone {compute:,.0f}; "
                  f"scheduler bound, no-op tasks through one scheduler {scheduler:,.0f}); output {min(compute, scheduler) * house_bytes / 1e9:.1f} GB/hour")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
