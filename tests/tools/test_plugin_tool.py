"""A tool is one file in a plugin: a module outside povagent (``plugins/zoom.py`` here, named
under a pipeline's ``plugins:``) registers ``zoom``, and an active run offers it, describes it
in the preamble, runs the model's call, renders its view and records it; rows made with another
set of tools are another pipeline."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import ConfigError
from povagent.results.episode import read_record
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, Reply

pytestmark = pytest.mark.timeout(120)

ZOOM = Path(__file__).parent / "plugins" / "zoom.py"
BUILT_IN = ["go_to_frame", "turn", "tilt", "move", "ask", "answer"]


def calls(*pairs: tuple[str, object]) -> Reply:
    return Reply(None, tool_calls=tuple({"name": n, "arguments": a} for n, a in pairs))


def write_pipeline(dataset: Path, folder: Path, server: LoopbackServer, *, zoom: bool) -> Path:
    """An active pipeline beside ``folder``; with ``zoom``, the plugin file beside it and named."""
    doc = {
        "dataset": {"path": str(dataset)},
        "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": server.url,
                                                   "api_key_env": "POVAGENT_TEST_KEY"}},
        "strategy": {"name": "active", "options": {"max_actions": 4}},
        "parser": "active",
        "scorers": ["official"],
        "retry": {"attempts": 1},
        "output": str(folder),
    }  # fmt: skip
    if zoom:
        shutil.copy(ZOOM, folder.parent / "zoom.py")
        doc["plugins"] = ["zoom.py"]
    path = folder.parent / ("zoom.yaml" if zoom else "built-in.yaml")
    path.write_text(yaml.safe_dump(doc))
    return path


@pytest.fixture
def model(monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-not-a-key")
    with LoopbackServer(reply="I cannot tell.", max_lifetime_s=100, fetch_images=True) as server:
        yield server


def test_a_plugin_tool_is_offered_and_described_with_the_built_ins(generated_release, tmp_path, model):
    model.script(calls(("answer", {"image": "frame 0", "x": 10, "y": 20})))
    run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=True)))
    (request,) = model.requests
    assert [t["function"]["name"] for t in request.body["tools"]] == [*BUILT_IN, "zoom"]
    prompt = request.body["messages"][0]["content"][-1]["text"]
    assert "ask(question) asks the person who spoke; zoom(factor) narrows the field of view." in prompt
    assert "Each go_to_frame, turn, tilt, move and zoom returns a new view" in prompt


def test_a_call_of_a_plugin_tool_runs_renders_its_view_and_is_recorded(generated_release, tmp_path, model):
    model.script(calls(("zoom", {"factor": 2})), calls(("answer", {"image": "view 1", "x": 100, "y": 200})))
    run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=True)))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    record = read_record(row.exchanges[-1].raw)
    assert row.status == "answered"
    step, _ = record.steps
    assert (step.action, step.valid, step.view) == ("zoom", True, 1)
    assert step.observation.startswith("View 1: zoomed in 2 times; now")
    assert record.views[0].camera.fov == record.start.fov / 2 and record.counts.actions == 1
    assert (tmp_path / "run" / "views" / f"{record.views[0].sha256}.png").is_file()
    assert record.answer.image == "view 1" and record.answer.camera.fov == record.start.fov / 2


def test_a_plugin_tool_refusing_its_arguments_is_an_invalid_call_naming_it(generated_release, tmp_path, model):
    model.script(calls(("zoom", {"factor": 0.5})), calls(("answer", {"image": "frame 0", "x": 1, "y": 2})))
    run_pipeline(load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=True)))
    record = read_record(read_rows(tmp_path / "run" / "results.jsonl")[0].exchanges[-1].raw)
    assert record.steps[0].observation == "invalid call: zoom: factor must be at least 1, got 0.5"
    assert record.counts.invalid_calls == 1 and record.views == []


def test_rows_made_with_another_set_of_tools_are_another_pipeline(generated_release, tmp_path, model):
    model.script(calls(("answer", {"image": "frame 0", "x": 1, "y": 2})))
    built_in = load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=False))
    run_pipeline(built_in)
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.config_hash == built_in.config_hash()
    with_zoom = load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=True))
    with pytest.raises(ConfigError, match=r"holds rows of a different pipeline"):
        run_pipeline(with_zoom)
    assert len(model.requests) == 1


def test_a_dry_run_of_a_finished_run_with_a_plugin_tool_plans_its_keys_done(generated_release, tmp_path, model):
    from povagent.dataset.loader import load_dataset
    from povagent.run.pending import pending_keys

    model.script(calls(("answer", {"image": "frame 0", "x": 1, "y": 2})))
    config = load_pipeline(write_pipeline(generated_release, tmp_path / "run", model, zoom=True))
    run_pipeline(config)
    assert read_rows(tmp_path / "run" / "results.jsonl")[0].config_hash != config.config_hash()  # the tools are in it
    assert pending_keys(config, load_dataset(generated_release)) == (1, 1, [])


def test_show_prompt_describes_a_plugin_tool_the_run_would_offer(generated_release, tmp_path, model):
    from typer.testing import CliRunner

    from povagent.cli import app

    path = write_pipeline(generated_release, tmp_path / "run", model, zoom=True)
    result = CliRunner().invoke(app, ["show-prompt", str(path), "--instance", "train_house_00000/pair_000/front/a", "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    assert "zoom(factor) narrows the field of view" in " ".join(result.output.split())
