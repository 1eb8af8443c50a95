"""Check: ``examples/robot_app.py`` run as the README runs it (no argument) solves the house it
generates on the spot.

    python benchmarks/robot_app_as_is.py

The test suite (``tests/examples/test_robot_app.py``) runs the example on the suite's generated
set (``--dataset``) so that no house is generated twice; this check runs it with no argument, so
the example generates its own house (seed 0, 12 frames) in a temporary folder, and makes the
suite's checks: exit 0, perception the SIMULATION, a frame of 12 at 640x480, a goal solved by
geometry (not back-projected), within 0.05 m of the truth (height in z) and no fallback.
Prints what is wrong, or "ok"; exits 1 on any problem.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "robot_app.py"
#: Simulated exact perception: the goal is the ground truth within the box fit's error (m).
GOAL_TOLERANCE = 0.05


def _point(text: str) -> np.ndarray:
    found = re.match(r"\s*\(([-\d.]+), ([-\d.]+), ([-\d.]+)\) m in the map frame", text)
    if found is None:
        raise ValueError(f"not a point in the map frame: {text!r}")
    return np.array([float(v) for v in found.groups()])


def problems(returncode: int, out: str, err: str) -> list[str]:
    """What is wrong with one run of the example (empty when it is clean and on target)."""
    if returncode != 0:
        return [f"exit {returncode}: {err[-2000:]}"]
    lines = dict(line.split(":", 1) for line in out.splitlines() if ":" in line and not line.startswith(" "))
    found = []
    if not lines.get("perception", "").strip().startswith("SIMULATION"):
        found.append("perception is not the SIMULATION")
    if not re.match(r"\s*\d+ of 12 \(640x480\)", lines.get("frame", "")):
        found.append(f"frame line: {lines.get('frame')!r}")
    if "(geometry)" not in lines.get("3D goal", ""):
        found.append(f"the goal was not solved by geometry: {lines.get('3D goal')!r}")
    try:
        goal, truth = _point(lines["3D goal"]), _point(lines["truth"])
    except (KeyError, ValueError) as exc:
        return [*found, f"no goal or truth: {exc}"]
    if np.linalg.norm(goal - truth) >= GOAL_TOLERANCE:
        found.append(f"goal {goal} is {np.linalg.norm(goal - truth):.3f} m from the truth {truth}")
    if abs(goal[2] - truth[2]) >= GOAL_TOLERANCE:
        found.append(f"height (z) {goal[2]} differs from the truth's {truth[2]}")
    if "fallbacks: none" not in out:
        found.append("the solver fell back")
    return found


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="robot_app_as_is_") as cwd:
        done = subprocess.run([sys.executable, str(EXAMPLE)], capture_output=True, text=True, timeout=600, cwd=cwd)
    found = problems(done.returncode, done.stdout, done.stderr)
    for problem in found:
        print(f"FAIL: {problem}")
    if not found:
        print("ok: the example generated its house and put the goal on the truth")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
