"""The report reads exactly what the real sweep runner writes (povagent.run.sweep + baselines)."""

from __future__ import annotations

import pytest
import yaml
from table_rows import system_row

from povagent.report.baseline import CENTER_SYSTEM
from povagent.report.build import write_report
from povagent.report.paper_tables import main_table


@pytest.fixture(scope="module")
def real_sweep(tmp_path_factory, mini_root):
    from povagent.run.sweep import run_sweep

    base = tmp_path_factory.mktemp("real_sweep")
    (base / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root.resolve())},
        "backend": {"name": "center", "options": {"frame_policy": "first"}},
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official"],
        "output": str(base / "unused"),
    }))
    (base / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "pipeline.yaml",
        "output": str(base / "sweep"),
        "axes": {"backend": ["center", "oracle"], "conditions": ["a", "c"]},
    }))
    run_sweep(base / "sweep.yaml", quiet=True)
    return base / "sweep"


def test_report_of_a_real_sweep_merges_condition_cells_into_systems(real_sweep, tmp_path):
    result = write_report(real_sweep, tmp_path / "rep", n_boot=0)
    assert [s.system for s in result.analysis.systems] == ["center", "oracle"]
    assert result.analysis.conditions == ["a", "c"]
    # the sweep has its own center cell: the report computes none and it equals what the
    # report would have computed (same "center, first frame" policy)
    assert CENTER_SYSTEM not in [s.system for s in result.analysis.systems]
    center = system_row(main_table(result.analysis), "center")
    oracle = system_row(main_table(result.analysis), "oracle")
    assert center.reference and oracle.reference
    assert [c.value for c in oracle.cells] == pytest.approx([0.0, 0.0], abs=1e-3)
    assert result.gallery.drawn > 0 and result.gallery.without_image == 0
