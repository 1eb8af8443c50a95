"""The active strategy end to end over HTTP: litellm sends the tools, the loopback server answers
with scripted tool calls, the views come back as labelled images, the row is scored in the
camera of the view answered in; hostile calls and text answers never crash a run."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from PIL import Image
from typer.testing import CliRunner

from povagent.cli import app
from povagent.config.pipeline import load_pipeline
from povagent.dataset.loader import load_dataset
from povagent.errors import WriteTargetError
from povagent.geometry.camera import Camera
from povagent.plugins import get_plugin_host
from povagent.results.episode import read_record
from povagent.results.rows import read_rows
from povagent.run.run_folder import MARKER
from povagent.run.runner import run_pipeline
from povagent.scoring.normalized_l2 import normalized_l2, project_ground_truth
from povagent.testing.loopback_server import LoopbackServer, Reply

pytestmark = pytest.mark.timeout(120)


def calls(*pairs: tuple[str, object]) -> Reply:
    """A reply of tool calls only (content null), as a model calling functions sends it."""
    return Reply(None, tool_calls=tuple({"name": n, "arguments": a} for n, a in pairs))


def run_active(dataset: Path, folder: Path, server: LoopbackServer, **strategy) -> tuple:
    doc = {
        "dataset": {"path": str(dataset)},
        "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": server.url,
                                                   "api_key_env": "POVAGENT_TEST_KEY"}},
        "strategy": {"name": "active", "options": strategy},
        "parser": "active",
        "scorers": ["official"],
        "retry": {"attempts": 1},
        "output": str(folder),
    }  # fmt: skip
    (folder.parent / "pipeline.yaml").write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(folder.parent / "pipeline.yaml"))
    (row,) = read_rows(folder / "results.jsonl")
    return row, read_record(row.exchanges[-1].raw)


@pytest.fixture
def model(monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-not-a-key")
    with LoopbackServer(reply="I cannot tell.", max_lifetime_s=100, fetch_images=True) as server:
        yield server


def test_the_whole_episode_runs_over_http_and_is_scored_in_the_view_answered_in(generated_release, tmp_path, model):
    model.script(calls(("go_to_frame", {"frame": 1}), ("turn", {"degrees": 10})),
                 calls(("answer", {"image": "view 2", "x": 100, "y": 200})))  # fmt: skip
    row, record = run_active(generated_release, tmp_path / "run", model)
    first, second = (r.body for r in model.requests)
    assert [t["function"]["name"] for t in first["tools"]] == list(get_plugin_host().tools().names)
    roles = [m["role"] for m in second["messages"]]
    assert roles == ["user", "assistant", "tool", "tool", "user"]
    assert [c["function"]["name"] for c in second["messages"][1]["tool_calls"]] == ["go_to_frame", "turn"]
    assert second["messages"][2]["tool_call_id"] == second["messages"][1]["tool_calls"][0]["id"]
    views = [p for p in second["messages"][4]["content"] if p["type"] == "text"]
    assert views[0]["text"].startswith("View 1: at frame 1") and views[1]["text"].startswith("View 2: turned 10 degrees")
    # the images the server received are the views the run folder holds, by content
    sent = [i.sha256 for i in model.requests[1].images][-2:]
    assert sent == [v.sha256 for v in record.views]
    assert all((tmp_path / "run" / "views" / f"{s}.png").is_file() for s in sent)
    # scored in view 2's camera: recomputed here from the camera the row holds
    cam = record.answer.camera
    instance = load_dataset(generated_release).instance(row.instance_id)
    gt = project_ground_truth(instance.target, Camera((cam.x, cam.y, cam.z), cam.yaw, cam.horizon, cam.fov))
    assert row.scores["official"]["l2"] == pytest.approx(normalized_l2(100, 200, 512, 512, gt.u, gt.v))
    assert (record.counts.actions, record.counts.views, record.answer.image) == (2, 2, "view 2")


def test_hostile_tool_calls_become_typed_observations_and_the_run_goes_on(generated_release, tmp_path, model):
    hostile = [("fly", {}), ("turn", {}), ("turn", {"degrees": 1, "x": 2}), ("move", {"forward": "1", "right": 0}),
               ("tilt", '{"degrees": NaN}'), ("tilt", '{"degrees": Infinity}'), ("move", '{"forward": 1e308, "right": 0}'),
               ("go_to_frame", {"frame": 99}), ("turn", "not json")]  # fmt: skip
    flood = hostile + [("turn", {"degrees": 1})] * (100 - len(hostile))
    model.script(calls(*flood), calls(("answer", {"image": "view 1", "x": 1, "y": 2})))
    row, record = run_active(generated_release, tmp_path / "run", model, max_actions=10)
    assert row.status == "answered" and row.error_type is None
    assert record.counts.invalid_calls == 9 and record.counts.actions == 10 and record.counts.refused_over_budget == 90
    assert record.counts.views == 1
    tool_results = [m["content"] for m in model.requests[1].body["messages"] if m["role"] == "tool"]
    assert len(tool_results) == 100 and all(t.startswith("invalid call:") for t in tool_results[:9])


def test_a_text_answer_in_the_official_json_is_accepted_and_labelled(generated_release, tmp_path, model):
    model.script('{"selected_image": 1, "x": 10, "y": 20}')
    row, record = run_active(generated_release, tmp_path / "run", model)
    assert record.answer.via == "text" and record.answer.image == "frame 1"
    assert row.parse.repair == "answered in text (official JSON), not with the answer tool"
    assert row.parse.selected_image == 1 and row.scores["official"]["answered"]


def test_a_model_that_never_answers_is_a_recorded_non_response_within_the_turn_limit(generated_release, tmp_path, model):
    model.reply = calls(("ask", {"question": "What were you doing?"}))
    row, record = run_active(generated_release, tmp_path / "run", model, max_actions=2)
    assert row.status == "parse_error" and len(model.requests) == 4  # max_turns = max_actions + 2
    assert record.answer is None and record.end == "no answer within 4 turns" and record.counts.questions == 2


def test_a_key_echoed_in_tool_call_ids_names_arguments_and_text_reaches_no_file(generated_release, tmp_path, monkeypatch):
    # The variable's name matches no secret-looking pattern: only knowing api_key_env finds it.
    key = "lab-key-4f9a8c7e2b1d"
    monkeypatch.setenv("POVAGENT_ECHO_VAR", key)

    def echo(request) -> Reply:
        sent = request.headers["authorization"]
        if not any(m["role"] == "tool" for m in request.body["messages"]):
            return Reply(f"looking around ({sent})", tool_calls=(
                {"id": f"call-{sent}", "name": "turn", "arguments": {"degrees": 5}},
                {"name": f"fly{key}", "arguments": {}},
                {"name": "tilt", "arguments": {"degrees": 5, "why": sent}},
            ))  # fmt: skip
        return Reply(f"done ({sent})", tool_calls=({"id": f"end-{key}", "name": "answer", "arguments": {"image": "view 1", "x": 1, "y": 2}},))

    with LoopbackServer(reply=echo, max_lifetime_s=100) as server:
        doc = {
            "dataset": {"path": str(generated_release)},
            "instances": {"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1},
            "backend": {"name": "litellm", "options": {"model": "openai/echo", "api_base": server.url, "api_key_env": "POVAGENT_ECHO_VAR"}},
            "strategy": {"name": "active", "options": {"max_actions": 4}},
            "parser": "active",
            "scorers": ["official"],
            "retry": {"attempts": 1},
            "output": str(tmp_path / "run"),
        }  # fmt: skip
        (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump(doc))
        run_pipeline(load_pipeline(tmp_path / "pipeline.yaml"))
        assert key in server.requests[-1].headers["authorization"]  # it was sent, and echoed
    result = CliRunner().invoke(app, ["report", str(tmp_path / "run"), "--bootstrap", "0"])
    assert result.exit_code == 0, result.output
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "answered" and "[REDACTED]" in row.exchanges[1].prompt  # echoed, then redacted
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert any(p.suffix == ".js" for p in written) and any(p.name == "report.html" for p in written)
    assert [str(p) for p in written if key.encode() in p.read_bytes()] == []


def test_a_planted_view_with_other_bytes_is_rendered_again_on_resume_and_the_key_answered(generated_release, tmp_path, model):
    script = (calls(("go_to_frame", {"frame": 1})), calls(("answer", {"image": "view 1", "x": 1, "y": 2})))
    model.script(*script)
    row, record = run_active(generated_release, tmp_path / "run", model)
    view = tmp_path / "run" / "views" / f"{record.views[0].sha256}.png"
    rendered = view.read_bytes()
    view.write_bytes(Image.new("RGB", (8, 8)).tobytes())  # other bytes under the view's name
    (tmp_path / "run" / "results.jsonl").write_bytes(b"")  # the key runs again, as after a kill
    model.script(*script)
    row, record = run_active(generated_release, tmp_path / "run", model)
    assert row.status == "answered" and row.error_type is None
    assert view.read_bytes() == rendered and model.requests[-1].images[-1].sha256 == record.views[0].sha256


def test_a_resumed_run_whose_views_folder_is_a_link_is_refused_in_one_line(generated_release, tmp_path, model):
    outside = tmp_path / "outside"
    outside.mkdir()
    run = tmp_path / "run"
    run.mkdir()
    (run / MARKER).write_text('{"format": 1, "kind": "run"}\n')
    (run / "views").symlink_to(outside, target_is_directory=True)
    with pytest.raises(WriteTargetError, match=r"views: is a symbolic link"):
        run_active(generated_release, run, model)
    assert list(outside.iterdir()) == [] and model.requests == []
