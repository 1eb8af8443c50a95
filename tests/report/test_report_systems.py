"""A system is a run, never a merge (povagent/report/systems.py): two run folders that look alike
by their configs stay two systems unless the user pools them, and the report says when it pooled."""

from __future__ import annotations

import shutil

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent.report.build import write_report
from povagent.report.collect import collect as collect_runs
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer

KEY_VARIABLE = "POVAGENT_SYSTEMS_TEST_KEY"


@pytest.fixture(scope="module", autouse=True)
def _key():
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(KEY_VARIABLE, "sk-test")
        yield


def _served_run(root, release, name: str, server: LoopbackServer, label: str | None = None):
    """``openai/any`` against ``server``, as a training loop serves a base and a fine-tuned checkpoint."""
    config = {
        "dataset": {"path": str(release)}, "strategy": "basic", "parser": "official", "instances": {"conditions": ["c"]},
        "backend": {"name": "litellm", "options": {"model": "openai/any", "api_base": server.url, "api_key_env": KEY_VARIABLE}},
        "retry": {"attempts": 1}, "timeout": 20, "cache": False, "output": str(root / name),
    }  # fmt: skip
    if label is not None:
        config["label"] = label
    (root / f"{name}.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    return run_pipeline(load_pipeline(root / f"{name}.yaml")).run_dir


@pytest.fixture(scope="module")
def two_servers_one_model_name(tmp_path_factory):
    """Two runs of ``openai/any``: one server answers every instance, the other never does."""
    from povagent.testing.pytest_plugin import write_release

    root = tmp_path_factory.mktemp("systems")
    release = write_release(root / "dataset", houses=1, pairs=3, pair_directions=3, frames=3)
    runs = root / "runs"
    runs.mkdir()
    with LoopbackServer(reply='{"image": 1, "x": 100, "y": 100}', max_lifetime_s=120) as base, \
         LoopbackServer(reply="I cannot tell.", max_lifetime_s=120) as tuned:  # fmt: skip
        _served_run(runs, release, "base", base)
        _served_run(runs, release, "tuned", tuned)
    return root, release, runs


def _response_rates(collection) -> dict[str, float]:
    rates: dict[str, list[bool]] = {}
    for o in collection.observations:
        rates.setdefault(o.system, []).append(o.answered)
    return {s: sum(v) / len(v) for s, v in rates.items()}


def test_two_runs_of_one_model_name_against_two_servers_are_two_systems(two_servers_one_model_name):
    _, _, runs = two_servers_one_model_name
    c = collect_runs(runs)
    assert c.systems == ["openai/any · basic (base)", "openai/any · basic (tuned)"]
    assert _response_rates(c) == {"openai/any · basic (base)": 1.0, "openai/any · basic (tuned)": 0.0}
    assert c.poolings == []


def test_the_report_shows_two_systems_and_says_nothing_was_pooled(two_servers_one_model_name):
    root, _, runs = two_servers_one_model_name
    result = write_report(runs, root / "report", n_boot=20, gallery=False)
    assert [s.system for s in result.analysis.model_systems] == ["openai/any · basic (base)", "openai/any · basic (tuned)"]
    assert result.poolings == [] and not any("Pooled" in n for n in result.analysis.notes)


def test_pooling_is_only_on_request_and_the_report_says_it_pooled(two_servers_one_model_name):
    root, _, runs = two_servers_one_model_name
    result = write_report(runs, root / "pooled", n_boot=20, gallery=False, pool=True)
    assert [s.system for s in result.analysis.model_systems] == ["openai/any · basic"]
    (pooling,) = result.poolings
    assert pooling.runs == ("base", "tuned") and pooling.reason == "asked"
    assert any(n.startswith("Pooled 2 runs into the system 'openai/any · basic' (--pool was given)") for n in result.analysis.notes)
    assert "Pooled 2 runs" in (root / "pooled" / "report.html").read_text(encoding="utf-8")


def test_a_label_names_the_system_and_rows_carry_it(tmp_path, two_servers_one_model_name):
    _, release, _ = two_servers_one_model_name
    with LoopbackServer(reply='{"image": 1, "x": 5, "y": 5}', max_lifetime_s=60) as server:
        run = _served_run(tmp_path, release, "step120", server, label="fine-tuned step 120")
    assert {r.label for r in read_rows(run / "results.jsonl")} == {"fine-tuned step 120"}
    assert collect_runs(run).systems == ["fine-tuned step 120"]


def test_runs_sharing_an_explicit_label_pool_and_say_so(two_servers_one_model_name, tmp_path):
    _, _, runs = two_servers_one_model_name
    for name in ("base", "tuned"):
        shutil.copytree(runs / name, tmp_path / name)
        config = yaml.safe_load((tmp_path / name / "config.yaml").read_text(encoding="utf-8"))
        (tmp_path / name / "config.yaml").write_text(yaml.safe_dump({**config, "label": "both servers"}), encoding="utf-8")
    c = collect_runs(tmp_path)
    assert c.systems == ["both servers"]
    assert [(p.system, p.reason) for p in c.poolings] == [("both servers", "label")]


def test_same_named_cells_of_a_sweep_stay_apart_by_their_folder_names(make_sweep):
    sweep = make_sweep([{"model": "mock-a", "seed": 1}, {"model": "mock-a", "seed": 2, "noise": 5.0}])
    assert collect_runs(sweep).systems == ["mock-a · basic (cell_00)", "mock-a · basic (cell_01)"]


@pytest.mark.parametrize("label", ["", "   ", "x" * 121])
def test_a_label_that_names_nothing_or_too_much_is_refused_at_load(tmp_path, label):
    (tmp_path / "p.yaml").write_text(yaml.safe_dump({"dataset": {"path": "d"}, "backend": "center", "output": "o", "label": label}))
    with pytest.raises(ConfigError, match="label"):
        load_pipeline(tmp_path / "p.yaml")


def test_a_real_sweep_over_two_servers_of_one_model_name_reports_two_systems(two_servers_one_model_name, tmp_path):
    from povagent.run.sweep import run_sweep

    _, release, _ = two_servers_one_model_name
    with LoopbackServer(reply='{"image": 1, "x": 100, "y": 100}', max_lifetime_s=120) as base, \
         LoopbackServer(reply="I cannot tell.", max_lifetime_s=120) as tuned:  # fmt: skip
        backends = [{"name": "litellm", "options": {"model": "openai/any", "api_base": s.url, "api_key_env": KEY_VARIABLE}} for s in (base, tuned)]
        (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump({
            "dataset": {"path": str(release)}, "backend": backends[0], "strategy": "basic", "parser": "official",
            "instances": {"conditions": ["c"]}, "retry": {"attempts": 1}, "timeout": 20, "cache": False, "output": str(tmp_path / "unused"),
        }))  # fmt: skip
        (tmp_path / "sweep.yaml").write_text(yaml.safe_dump({"base": "pipeline.yaml", "output": str(tmp_path / "sweep"), "axes": {"backend": backends}}))
        run_sweep(tmp_path / "sweep.yaml", quiet=True)
    c = collect_runs(tmp_path / "sweep")
    assert len(c.systems) == 2 and all(s.startswith("openai/any · basic (") for s in c.systems)
    assert sorted(_response_rates(c).values()) == [0.0, 1.0]
