"""How long the README's test command takes: wall time and CPU time of the whole suite.

    python benchmarks/bench_suite.py                 # runs the README's pytest command (-q added) and times it
    python benchmarks/bench_suite.py --timed LOG     # reads a `/usr/bin/time -v` log of that command instead

The suite runs in this checkout's ``.venv`` (as the README installs it). Wall time moves with
the machine's load; CPU time (user + system of pytest and every process it starts) much less,
so both are recorded with the load average. Figures: the suite's wall time (goal: 12 minutes
on an idle machine) and CPU time (goal: 450 s).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import time
from pathlib import Path

from results_file import figure, record

ROOT = Path(__file__).resolve().parent.parent


def readme_pytest_arguments() -> list[str]:
    """The arguments the README's test command gives ``.venv/bin/pytest`` (workers and all)."""
    for line in (ROOT / "README.md").read_text().splitlines():
        if "&& .venv/bin/pytest" in line:
            return line.split("&& .venv/bin/pytest", 1)[1].split()
    raise SystemExit("README.md: no test command ending in `.venv/bin/pytest ...` found")


def _from_time_log(text: str) -> tuple[float, float]:
    """(wall s, CPU s) from GNU time's verbose output."""
    user = float(re.search(r"User time \(seconds\): ([\d.]+)", text).group(1))  # type: ignore[union-attr]
    system = float(re.search(r"System time \(seconds\): ([\d.]+)", text).group(1))  # type: ignore[union-attr]
    clock = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)", text).group(1)  # type: ignore[union-attr]
    wall = 0.0
    for part in clock.split(":"):
        wall = wall * 60 + float(part)
    return wall, user + system


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--timed", type=Path, help="a /usr/bin/time -v log of the README's pytest command")
    ap.add_argument("--load", help="with --timed: the load average seen while that run ran (recorded as said)")
    args = ap.parse_args()
    load = os.getloadavg()
    if args.timed is not None:
        wall, cpu = _from_time_log(args.timed.read_text())
        command = f"/usr/bin/time -v .venv/bin/pytest {' '.join(readme_pytest_arguments())} (then python benchmarks/bench_suite.py --timed LOG)"
    else:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        subprocess.run([str(ROOT / ".venv" / "bin" / "pytest"), "-q", *readme_pytest_arguments()], cwd=ROOT, check=False)
        wall = time.monotonic() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        command = None
    print(f"suite: {wall / 60:.1f} min wall, {cpu:.0f} s CPU (load at start {load[0]:.1f})")
    record("bench_suite", [
        figure("the README's test command, wall time", round(wall / 60, 1), "min", target="<= 12 on an idle machine"),
        figure("the README's test command, CPU time", round(cpu), "s", target="<= 450"),
    ], command=command, note=f"load average during the run: {args.load}" if args.timed else f"load average at the start {load[0]:.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
