"""A perception simulation is labelled a simulation in every report, never counted as a model."""

from __future__ import annotations

import yaml

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.report.collect import collect
from povagent.report.systems import simulation_label
from povagent.run.runner import run_pipeline


def run(tmp_path, mini_root, name, backend, strategy):
    path = tmp_path / f"{name}.yaml"
    doc = {"dataset": {"path": str(mini_root)}, "backend": backend, "strategy": strategy, "parser": "json",
           "instances": {"houses": ["train_house_00001"]}, "output": str(tmp_path / "runs" / name)}
    path.write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(path))


def test_the_simulated_backend_is_a_labelled_simulation_in_tables_plots_and_cards(tmp_path, mini_root):
    sim = {"name": "simulated", "options": {"pixel_sigma": 10, "wrong_furniture_rate": 0.2}}
    run(tmp_path, mini_root, "sim", sim, "geometric")
    run(tmp_path, mini_root, "center", {"name": "center"}, "basic")
    systems = collect(tmp_path / "runs").systems
    label = "simulation (sigma 10 px, wrong furniture 0.2)"
    assert any(s.startswith(label) for s in systems)
    result = write_report(tmp_path / "runs", out=tmp_path / "report", n_boot=0)
    assert not any("simulation" in s.system for s in result.analysis.model_systems)
    assert any("simulation" in s.system for s in result.analysis.systems)
    tables = (tmp_path / "report" / "tables.md").read_text()
    assert f"*{label} · geometric*" in tables  # a reference row, in italics, never bolded
    plots = "".join(p.read_text() for p in (tmp_path / "report" / "plots").glob("*.svg"))
    assert label in plots and "simulated" not in plots.replace("simulation", "")
    assert label in (tmp_path / "report" / "report.html").read_text()


def test_a_simulation_without_noise_says_so():
    assert simulation_label({}) == "simulation (no noise)"
    assert simulation_label({"pixel_sigma": 0, "miss_rate": 0.1}) == "simulation (miss 0.1)"
