"""All five interventions run end to end through ``povagent sweep`` with an offline backend."""

from __future__ import annotations

import json

import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.results.rows import read_rows

INTERVENTIONS = ["basic", "o-plot", "oa-plot", "cot", "spatial-cot"]


def test_every_intervention_runs_in_a_sweep_over_the_fixture(tmp_path, mini_root):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({
        "base": {
            "dataset": {"path": str(mini_root)},
            "instances": {"conditions": ["a"]},
            "backend": {"name": "center"},
            "output": str(tmp_path / "unused"),
        },
        "output": str(tmp_path / "out"),
        "axes": {"strategy": INTERVENTIONS},
    }))
    result = CliRunner().invoke(app, ["sweep", str(sweep)])
    assert result.exit_code == 0, result.output
    index = json.loads((tmp_path / "out" / "sweep.json").read_text())
    cells = {cell["name"]: cell for cell in index["cells"]}
    assert sorted(cells) == sorted(INTERVENTIONS)
    rows = {name: read_rows(tmp_path / "out" / name / "results.jsonl") for name in INTERVENTIONS}
    for name in INTERVENTIONS:
        assert cells[name]["status"] == "done"
        assert rows[name] and all(r.strategy == name and r.status == "answered" for r in rows[name])

    def shown(name):
        return {h for r in rows[name] for h in r.exchanges[0].image_hashes}

    # the marker strategies show marked frames; CoT and S-CoT show the frames as they are
    assert shown("oa-plot") != shown("basic") and shown("cot") == shown("basic")


def test_the_paper_ablation_sweep_sends_what_the_ablation_scripts_sent():
    """examples/sweeps/paper_ablation.yaml: every cell shows the first 30 frames (ab0 .. ab4),
    Basic / O-Plot / O&A-Plot 256 new tokens, CoT / S-CoT 1,024 (the Transformers run)."""
    from pathlib import Path

    from povagent.plugins import get_plugin_host
    from povagent.run.sweep import expand_sweep

    sweep = Path(__file__).resolve().parents[2] / "examples" / "sweeps" / "paper_ablation.yaml"
    _, cells = expand_sweep(sweep)
    host = get_plugin_host()
    budgets = {}
    for cell in cells:
        strategy = host.create("strategy", cell.config.strategy.name, cell.config.strategy.options)
        assert strategy.max_frames == 30, cell.name
        assert strategy.prompts.name == "runner"
        budgets[cell.config.strategy.name] = strategy.generation.max_tokens
    assert budgets == {"basic": 256, "o-plot": 256, "oa-plot": 256, "cot": 1024, "spatial-cot": 1024}
