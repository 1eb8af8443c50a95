"""The paper-table sweep YAMLs expand into the tables' cells and name the paper's models.

They need API keys and model servers, so they are checked here, not run.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent.plugins import get_plugin_host
from povagent.run.runner import create_components
from povagent.run.sweep import expand_sweep

SWEEPS = Path(__file__).resolve().parents[2] / "examples" / "sweeps"


def models_of(cells) -> set[str]:
    host = get_plugin_host()
    return {create_components(c.config, host).backend.model for c in cells}


def test_main_table_has_a_cell_per_model_condition_and_run():
    _, cells = expand_sweep(SWEEPS / "paper_main_table.yaml")
    assert len(cells) == 7 * 3 * 3
    assert {c.axes["conditions"] for c in cells} == {"a", "b", "c"}
    assert {c.config.parser.name for c in cells} == {"official"}


def test_main_table_names_the_papers_models():
    _, cells = expand_sweep(SWEEPS / "paper_main_table.yaml")
    assert models_of([c for c in cells if c.axes["conditions"] == "a" and c.axes["runs"] == "run0"]) == {
        "openai/gpt-5.4",
        "gemini/gemini-2.5-flash",
        "gemini/gemini-robotics-er-1.6-preview",
        "gemini/gemma-4-26b-a4b-it",
        "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
        "hosted_vllm/Qwen/Qwen3-VL-32B-Instruct",
        "hosted_vllm/OpenGVLab/InternVL3-38B",
    }


def test_given_only_rows_run_condition_c_with_each_models_parser():
    _, cells = expand_sweep(SWEEPS / "paper_main_table_given_only.yaml")
    assert len(cells) == 2 * 3
    assert all(c.config.instances.conditions == ["c"] for c in cells)
    pairs = {(c.config.backend.options["model"], c.config.parser.name) for c in cells}
    assert pairs == {("robopoint", "robopoint-official"), ("llama-3.2-vision", "official")}


def test_ablation_has_the_five_interventions_on_inferred_and_stated():
    _, cells = expand_sweep(SWEEPS / "paper_ablation.yaml")
    assert len(cells) == 5 * 2 * 3
    assert {c.config.strategy.name for c in cells} == {"basic", "o-plot", "oa-plot", "cot", "spatial-cot"}
    assert {c.axes["conditions"] for c in cells} == {"a", "b"}
    assert models_of(cells[:1]) == {"hosted_vllm/Qwen/Qwen3-VL-8B-Instruct"}


@pytest.mark.parametrize("name", ["paper_main_table", "paper_main_table_given_only", "paper_ablation"])
def test_every_cell_writes_to_its_own_folder(name):
    sweep, cells = expand_sweep(SWEEPS / f"{name}.yaml")
    outputs = [c.config.output for c in cells]
    assert len(set(outputs)) == len(outputs) and all(o.parent == sweep.output for o in outputs)
