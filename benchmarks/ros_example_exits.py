"""Check: ``examples/ros/play_to_node.py`` run many times in a row exits cleanly every time.

    python benchmarks/ros_example_exits.py [--runs 10] [--lanes 2]

The example once aborted at exit ("terminate called ...") in 2 runs of 10: a rare failure
needs many runs to show. The test suite runs the example once
(``tests/examples/test_ros_examples.py``); this check runs it ``--runs`` times, ``--lanes`` at a
time, each lane on its own ROS domain id (their graphs never meet), over the same generated
set as the suite's ``generated_release`` fixture (2 houses, seed 3, 12 frames, made once in a
temporary folder). Every run must exit 0 with no "terminate called" on stderr, say its
perception is the SIMULATION, answer ``ok`` and put the goal within 0.05 m of the truth.
Prints one line per run and a total; exits 1 if any run fails. Needs the ros extra.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "ros" / "play_to_node.py"
#: Simulated exact perception: the goal is the ground truth within the box fit's error (m).
GOAL_TOLERANCE = 0.05


def problem(returncode: int, out: str, err: str) -> str | None:
    """What is wrong with one run of the example, or None when it is clean and on target."""
    if returncode != 0 or "terminate called" in err:
        return f"exit {returncode}: {err[-300:]!r}"
    lines = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
    if not lines.get("perception", "").strip().startswith("SIMULATION") or lines.get("status", "").strip() != "ok":
        return f"not a simulated ok answer: {out[-300:]!r}"
    goal, truth = (np.array([float(v) for v in re.findall(r"-?\d+\.\d+", lines[k])[:3]]) for k in ("goal", "truth"))
    error = float(np.linalg.norm(goal - truth))
    return None if error < GOAL_TOLERANCE else f"goal {error:.3f} m from the truth"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--lanes", type=int, default=2)
    args = ap.parse_args()
    from povagent.generate import generate_dataset

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        dataset = folder / "POVBench"
        generate_dataset(dataset, houses=2, seed=3, frames=12, jobs=1, progress=False)
        env = {**os.environ, "ROS_LOG_DIR": str(folder)}
        base = 10 + (os.getpid() % 15) * args.lanes  # domain ids 10-39 (the ROS tests use 40-99)
        failures = 0
        for start in range(0, args.runs, args.lanes):
            t0 = time.monotonic()
            procs = []
            for lane in range(min(args.lanes, args.runs - start)):
                command = [sys.executable, str(EXAMPLE), "--dataset", str(dataset), "--domain-id", str(base + lane)]
                procs.append(subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=folder, env=env))
            for k, proc in enumerate(procs):
                out, err = proc.communicate(timeout=180)
                wrong = problem(proc.returncode, out, err)
                failures += wrong is not None
                print(f"run {start + k + 1}: {wrong or 'clean'} ({time.monotonic() - t0:.1f} s)")
    print(f"{args.runs - failures} of {args.runs} runs exited cleanly on target")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
