"""Which model answered is named everywhere a run's numbers are: the ``run`` header, every row
of ``results.jsonl``, ``summary.json``, each sweep cell (``sweep.json``, the console) and the
report's system labels. A model named by a profile is named by both (``qwen3-vl-8b =
hosted_vllm/Qwen/Qwen3-VL-8B-Instruct``); an offline baseline is its own model (``center``).
Rows written before rows named the model stay readable and take it from the config."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.report.collect import collect
from povagent.results.rows import ResultRow, model_label, read_rows
from povagent.testing.loopback_server import LoopbackServer

pytestmark = pytest.mark.timeout(300)  # litellm imports in seconds, much longer on a busy machine

PROFILE = "qwen3-vl-8b"
LITELLM_MODEL = "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct"


def write_yaml(path: Path, doc: dict) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def pipeline(tmp_path: Path, mini_root: Path, backend: dict, name: str = "run") -> dict:
    return {
        "dataset": str(mini_root),
        "instances": {"limit": 3},
        "backend": backend,
        "strategy": "basic",
        "parser": "official",
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 120,  # the first request waits for litellm's import
        "cache": False,
        "output": str(tmp_path / name),
    }


@pytest.fixture(scope="module")
def profile_run(tmp_path_factory, mini_root):
    """A 3-instance run of the ``qwen3-vl-8b`` profile against a loopback server: (run folder,
    the ``run`` command's output). One run for the module (litellm's import is slow); the
    report test works on a copy."""
    tmp_path = tmp_path_factory.mktemp("profile")
    with LoopbackServer(reply='{"selected_image": 0, "x": 100, "y": 120}', max_lifetime_s=280) as server:
        backend = {"name": "litellm", "options": {"model": PROFILE, "api_base": server.url}}
        doc = write_yaml(tmp_path / "p.yaml", pipeline(tmp_path, mini_root, backend))
        result = CliRunner().invoke(app, ["run", str(doc), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return tmp_path / "run", result.stdout


def test_the_run_header_names_the_profile_and_its_litellm_model(profile_run):
    out = " ".join(profile_run[1].split())  # the title wraps to the table's width
    assert f"(litellm {PROFILE} = {LITELLM_MODEL} / basic / official)" in out


def test_every_row_names_the_model_that_answered(profile_run):
    rows = read_rows(profile_run[0] / "results.jsonl")
    assert len(rows) == 3
    assert {(r.backend, r.model, r.profile) for r in rows} == {("litellm", LITELLM_MODEL, PROFILE)}
    raw = [json.loads(line) for line in (profile_run[0] / "results.jsonl").read_text().splitlines()]
    assert all(r["model"] == LITELLM_MODEL and r["profile"] == PROFILE for r in raw)


def test_the_summary_names_the_model(profile_run):
    summary = json.loads((profile_run[0] / "summary.json").read_text())
    assert summary["pipeline"]["model"] == LITELLM_MODEL and summary["pipeline"]["profile"] == PROFILE


def test_a_plain_litellm_string_is_named_as_written(tmp_path, mini_root):
    with LoopbackServer(reply='{"selected_image": 0, "x": 100, "y": 120}', max_lifetime_s=280) as server:
        backend = {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": server.url, "api_key_env": "POVAGENT_TEST_KEY"}}
        doc = write_yaml(tmp_path / "p.yaml", pipeline(tmp_path, mini_root, backend))
        result = CliRunner().invoke(app, ["run", str(doc), "--quiet"], env={"COLUMNS": "200", "POVAGENT_TEST_KEY": "x"})
    assert result.exit_code == 0, result.output
    assert "(litellm openai/loopback-vlm / basic / official)" in " ".join(result.stdout.split())
    assert {(r.model, r.profile) for r in read_rows(tmp_path / "run" / "results.jsonl")} == {("openai/loopback-vlm", None)}


def test_a_baseline_is_named_by_its_backend(tmp_path, mini_root):
    doc = write_yaml(tmp_path / "p.yaml", pipeline(tmp_path, mini_root, {"name": "center"}))
    result = CliRunner().invoke(app, ["run", str(doc), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "(center / basic / official)" in " ".join(result.stdout.split())
    assert {(r.model, r.profile) for r in read_rows(tmp_path / "run" / "results.jsonl")} == {("center", None)}
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["pipeline"]["model"] == "center"


def test_each_sweep_cell_names_its_model(tmp_path, mini_root):
    base = pipeline(tmp_path, mini_root, {"name": "center"}, name="unused")
    sweep = write_yaml(tmp_path / "s.yaml", {
        "base": base, "output": str(tmp_path / "sweep"),
        "axes": {"backend": ["center", {"name": "random", "options": {"seed": 0}}], "conditions": ["a", "c"]},
    })  # fmt: skip
    result = CliRunner().invoke(app, ["sweep", str(sweep), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    index = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert sorted((c["model"], c["profile"]) for c in index["cells"]) == [("center", None)] * 2 + [("random", None)] * 2
    # each finished cell's line names its model (a cell named just for its model says it already)
    for cell in index["cells"]:
        assert cell["name"] != cell["model"] and f"{cell['name']} ({cell['model']}):" in result.stdout


def test_a_row_without_a_model_field_is_read(tmp_path):
    """A row written before rows named their model: read, with no model and no profile."""
    line = json.dumps({"key": "h/p/left/a#0", "instance_id": "h/p/left/a", "house_id": "h", "pair_id": "p",
                       "direction": "left", "condition": "a", "status": "answered", "backend": "litellm"})  # fmt: skip
    (tmp_path / "results.jsonl").write_text(line + "\n")
    (row,) = read_rows(tmp_path / "results.jsonl")
    assert (row.model, row.profile, row.backend) == ("", None, "litellm")


def test_the_report_names_the_model_the_rows_name(profile_run, tmp_path):
    """The config is not the source when rows name the model: a config without the model
    option still gives the profile's label, and rows without it fall back to the config."""
    folder = tmp_path / "run"
    shutil.copytree(profile_run[0], folder)
    config = yaml.safe_load((folder / "config.yaml").read_text())
    config["backend"]["options"] = {}
    (folder / "config.yaml").write_text(yaml.safe_dump(config))
    assert collect(folder).systems == [f"{PROFILE} · basic"]

    config["backend"]["options"] = {"model": "from-the-config"}
    (folder / "config.yaml").write_text(yaml.safe_dump(config))
    rows = [ResultRow.model_validate_json(line) for line in (folder / "results.jsonl").read_text().splitlines()]
    old = [r.model_dump(mode="json", exclude={"model", "profile"}) for r in rows]
    (folder / "results.jsonl").write_text("".join(json.dumps(r) + "\n" for r in old))
    assert collect(folder).systems == ["from-the-config · basic"]


def test_model_label_names_profile_and_model():
    assert model_label(LITELLM_MODEL, PROFILE) == f"{PROFILE} = {LITELLM_MODEL}"
    assert model_label("openai/gpt-4o") == "openai/gpt-4o"
    assert model_label("center", None) == "center"
