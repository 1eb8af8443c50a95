"""Benchmark of the README's main command, ``povagent quickstart``, from an empty folder.

Run: ``python benchmarks/bench_quickstart.py [--rounds N] [--jobs N]``. Each round runs the
command in a fresh folder as a user would (a new process, offline) and prints its wall time,
its CPU time (user + sys of the command and its worker processes: the stable figure on a
shared machine, where wall time depends on the other load), the generation's own wall time as
the command reports it, and the 1-minute load average before and after. A second run in the
same folder (the resume: no new work) is timed too. Wall time on an idle machine is about the
CPU time divided by the cores used in parallel (the houses are generated one per core).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run_once(out: Path, jobs: int | None) -> dict[str, float]:
    """One ``povagent quickstart`` in ``out``: wall s, CPU s (user + sys, children included),
    generation wall s (as printed), load average before and after."""
    cmd = [sys.executable, "-m", "povagent.cli", "quickstart", "--out", str(out), "-q"] + ([] if jobs is None else ["--jobs", str(jobs)])
    load_before = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"quickstart failed ({done.returncode}):\n{done.stderr[-2000:]}")
    generation = re.search(r"done in ([\d.]+) s", done.stdout)
    return {
        "wall": wall,
        "cpu": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
        "generation_wall": float(generation.group(1)) if generation else 0.0,
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--jobs", type=int, default=None, help="passed to quickstart (default: its own, one per core)")
    args = parser.parse_args()
    print(f"cores usable: {len(os.sched_getaffinity(0))}")
    for r in range(args.rounds):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "qs"
            first = run_once(out, args.jobs)
            again = run_once(out, args.jobs)
        print(
            f"round {r + 1}: quickstart {first['wall']:.1f} s wall, {first['cpu']:.1f} s CPU (user+sys), "
            f"generation {first['generation_wall']:.1f} s wall; load average {first['load_before']:.1f} -> {first['load_after']:.1f}"
        )
        print(f"         again (resume, no new work): {again['wall']:.1f} s wall, {again['cpu']:.1f} s CPU; load {again['load_before']:.1f}")


if __name__ == "__main__":
    main()
