"""examples/robot_app.py runs the geometric solver end to end offline and prints a 3D goal
in the robot's map that matches the benchmark's ground truth.

The test gives the example the session's generated set (``--dataset``), so the house is not
generated a second time; ``benchmarks/robot_app_as_is.py`` runs it as the README does, with no
argument (it generates its own house), and makes the same checks."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "robot_app.py"
#: Simulated exact perception: the goal is the ground truth within the box fit's error (m).
GOAL_TOLERANCE = 0.05


def point(text: str) -> np.ndarray:
    x, y, z = re.match(r"\s*\(([-\d.]+), ([-\d.]+), ([-\d.]+)\) m in the map frame", text).groups()
    return np.array([float(x), float(y), float(z)])


def test_robot_app_solves_a_generated_house_offline_and_says_it_is_a_simulation(tmp_path, generated_release):
    proc = subprocess.run([sys.executable, str(SCRIPT), "--dataset", str(generated_release)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(":", 1) for line in proc.stdout.splitlines() if ":" in line and not line.startswith(" "))
    assert lines["perception"].strip().startswith("SIMULATION")
    assert re.match(r"\s*\d+ of 12 \(640x480\)", lines["frame"])
    assert "(geometry)" in lines["3D goal"]  # solved, not a pixel back-projected onto the floor
    goal, truth = point(lines["3D goal"]), point(lines["truth"])
    assert np.linalg.norm(goal - truth) < GOAL_TOLERANCE
    assert abs(goal[2] - truth[2]) < GOAL_TOLERANCE  # the map is z-up: height comes back in z
    assert "fallbacks: none" in proc.stdout


def test_robot_app_reports_a_missing_dataset(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--dataset", str(tmp_path / "missing")],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )
    assert proc.returncode == 1
    assert proc.stderr.startswith("error:") and "missing" in proc.stderr
