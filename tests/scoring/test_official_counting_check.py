"""The official-counting check (benchmarks/official_counting_check.py) passes: povagent's
``score --json`` on official run folders equals a reference written from the rules, to 1e-9."""

from __future__ import annotations

import importlib.util
from pathlib import Path

CHECK = Path(__file__).resolve().parents[2] / "benchmarks" / "official_counting_check.py"


def test_score_on_official_run_folders_equals_the_independent_reference(tmp_path):
    spec = importlib.util.spec_from_file_location("official_counting_check", CHECK)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(tmp_path) <= module.TOLERANCE
