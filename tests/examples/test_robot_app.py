"""examples/robot_app.py runs offline and prints a frame, a pixel and a 3D goal."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[2] / "examples" / "robot_app.py"


def test_robot_app_prints_frame_pixel_and_3d_goal_offline(tmp_path):
    proc = subprocess.run([sys.executable, str(SCRIPT)], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(":", 1) for line in proc.stdout.splitlines() if ":" in line)
    assert lines["frame"].strip().startswith("0 of 3 (1280x720)")
    assert lines["pixel"].strip().startswith("(640.0, 360.0)")
    # camera 1 m high, tilted 25 degrees down, heading +x: the centre ray meets the floor 1/tan(25) ahead
    assert lines["3D goal"].strip().startswith("(2.14, 0.00, 0.00) m in the map frame")


def test_robot_app_reports_a_bad_pipeline_file(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(SCRIPT), "--pipeline", str(tmp_path / "missing.yaml")],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )
    assert proc.returncode == 1
    assert proc.stderr.startswith("error:") and "missing.yaml: file not found" in proc.stderr
