"""The four short plugin examples of ``docs/reference/plugins.md`` (``examples/plugins/``), each run
through the real runner: a pipeline YAML names the example by its ``.py`` path under
``plugins:`` (relative to the YAML's folder, as the page shows), on a small synthetic release,
and the rows and ``summary.json`` show what the plugin did."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from PIL import Image

from povagent.config.pipeline import load_pipeline
from povagent.dataset import load_dataset
from povagent.errors import PluginError
from povagent.plugins import _import_module_or_file
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent_plugins.strategies.basic import BasicStrategy

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "plugins"
KEY_VARIABLE = "POVAGENT_EXAMPLE_KEY"


@pytest.fixture
def release(tiny_dataset) -> Path:
    """One house, one pair, two directions, three frames: 6 instances (2 per condition)."""
    return tiny_dataset(houses=1, pairs=1, pair_directions=2, frames=3)


@pytest.fixture
def pipeline(tmp_path, release, povagent_host):
    """``pipeline(example_file, **keys) -> Path``: a pipeline YAML in its own folder beside a
    copy of ``examples/plugins/<example_file>`` (as a user puts a one-file plugin next to
    their pipeline)."""

    def write(example: str, **keys: Any) -> Path:
        folder = tmp_path / "project"
        folder.mkdir(exist_ok=True)
        shutil.copy(EXAMPLES / example, folder / example)
        data: dict[str, Any] = {
            "plugins": [example],
            "dataset": {"path": str(release)},
            "backend": "center",
            "retry": {"attempts": 3, "initial_wait": 0.0, "max_wait": 0.01},
            "timeout": 10,
            "output": str(tmp_path / "run"),
            **keys,
        }
        path = folder / "pipeline.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return write


def run(path: Path):
    """The runner, as ``povagent run`` calls it; the rows it wrote."""
    result = run_pipeline(load_pipeline(path))
    return result, read_rows(result.run_dir / "results.jsonl")


def litellm_at(server) -> dict[str, Any]:
    """A litellm backend pointed at the loopback server."""
    return {"name": "litellm", "options": {"model": "openai/loopback-model", "api_base": server.url, "api_key_env": KEY_VARIABLE}}


def last_text(recorded) -> str:
    """The prompt text a request carried (its last text part)."""
    return [p["text"] for p in recorded.user_parts() if p.get("type") == "text"][-1]


# -- a. the strategy ------------------------------------------------------------------------------
def test_speaker_view_sends_the_basic_prompt_with_its_reminder_last(pipeline, release, loopback_server, monkeypatch):
    monkeypatch.setenv(KEY_VARIABLE, "sk-test")
    loopback_server.reply = lambda req: '{"selected_image": 0, "x": 10, "y": 20}' if len(req.image_urls()) > 1 else '{"x": 10, "y": 20}'
    _, rows = run(pipeline("speaker_view_strategy.py", backend=litellm_at(loopback_server), strategy="speaker-view"))
    reminder = _import_module_or_file(str(EXAMPLES / "speaker_view_strategy.py")).REMINDER
    basic = BasicStrategy()
    expected = sorted(f"{basic.prompt_text(i)}\n{reminder}" for i in load_dataset(release).instances())
    assert sorted(last_text(r) for r in loopback_server.requests) == expected
    assert len(rows) == 6 and {r.status for r in rows} == {"answered"} and {r.strategy for r in rows} == {"speaker-view"}


# -- b. the parser ----------------------------------------------------------------------------------
def test_image_at_reads_prose_answers_and_records_what_it_cannot_read(pipeline, loopback_server, monkeypatch):
    monkeypatch.setenv(KEY_VARIABLE, "sk-test")

    def reply(req) -> str:
        if len(req.image_urls()) == 1:  # Given: no frame asked
            return "The book is at (300, 411)."
        return "The book is on the floor in Image 2 at (120.5, 340)." if "left of the bed" in last_text(req) else "I cannot tell."

    loopback_server.reply = reply
    _, rows = run(pipeline("image_at_parser.py", backend=litellm_at(loopback_server), parser="image-at"))
    by_case = {(r.condition, r.direction): r for r in rows}
    framed = by_case[("a", "left")]
    assert framed.status == "answered" and framed.parser == "image-at"
    assert (framed.parse.selected_image, framed.parse.x, framed.parse.y) == (2, 120.5, 340.0)
    assert framed.prediction.image_path == "exploration_images/frame_002.png"
    given = by_case[("c", "right")]
    assert given.status == "answered" and (given.parse.selected_image, given.parse.x, given.parse.y) == (None, 300.0, 411.0)
    unread = by_case[("b", "right")]
    assert unread.status == "parse_error" and unread.parse.status == "unparseable"
    assert unread.parse.reason == "no (x, y) pair in the answer" and unread.scores == {}


def test_image_at_never_raises_on_hostile_text():
    parser = _import_module_or_file(str(EXAMPLES / "image_at_parser.py")).ImageAtParser()
    from povagent.answers.spec import AnswerSpec, frame_answer_schema

    spec = AnswerSpec(schema=frame_answer_schema(3, 512, 512), n_frames=3)
    for text in (
        "",
        "(",
        "Image 99999999999999999999 at (1e5, -3)",
        "Image " + "9" * 5000 + " at (1, 2)",
        f"({'9' * 5000}, 1) image 1",
        "(1, 2) but no frame",
        "\x00" * 10_000,
        "Image 1 at (600, 7)",
    ):
        parsed = parser.parse(text, spec)
        assert parsed.status in ("unparseable", "ok", "out_of_range")
    assert parser.parse("Image 1 at (600, 7)", spec).status == "out_of_range"


# -- c. the scorer ----------------------------------------------------------------------------------
def test_within_radius_calls_success_exactly_when_the_official_l2_is_within_it(pipeline):
    scorers = ["official", {"name": "within-radius", "options": {"radius": 0.2}}]
    result, rows = run(pipeline("within_radius_scorer.py", backend={"name": "center", "options": {"frame_policy": "cycle"}}, scorers=scorers))
    assert len(rows) == 6
    for row in rows:
        mine, official = row.scores["within-radius"], row.scores["official"]
        assert mine["l2"] == official["l2"] and mine["radius"] == 0.2
        assert mine["success"] is (official["l2"] is not None and official["l2"] <= 0.2)
    assert {r.scores["within-radius"]["success"] for r in rows} == {True, False}, "the set should hold a hit and a miss"
    summary = json.loads((result.run_dir / "summary.json").read_text())
    hits = sum(r.scores["within-radius"]["success"] for r in rows)
    assert summary["scorers"]["within-radius"]["success"] == {"n": 6, "true": hits, "rate": hits / 6}
    assert summary["scorers"]["within-radius"]["l2"]["mean"] == pytest.approx(summary["overall"]["mean_l2"])


def test_within_radius_refuses_a_radius_that_is_not_positive(pipeline):
    path = pipeline("within_radius_scorer.py", scorers=[{"name": "within-radius", "options": {"radius": -1}}])
    with pytest.raises(
        PluginError, match=r"scorer 'within-radius' \(config plugin .*within_radius_scorer.py\) rejected its options.*radius must be a positive number"
    ):
        run(path)


# -- d. the backend ---------------------------------------------------------------------------------
def paint_spot(png: Path, x: int, y: int) -> None:
    """A white pixel at (x, y) in an otherwise unchanged image."""
    pixels = np.asarray(Image.open(png).convert("RGB")).copy()
    pixels[y, x] = 255
    Image.fromarray(pixels).save(png)


def test_local_model_answers_retries_a_busy_device_and_records_a_permanent_failure(pipeline, release):
    house = release / "artifacts" / "train_house_00000"
    paint_spot(house / "img_from_observer" / "pair_0.png", 200, 150)
    paint_spot(house / "exploration_images" / "frame_001.png", 40, 300)
    backend = {"name": "local-brightest", "options": {"max_images": 3, "busy_every": 2}}
    result, rows = run(pipeline("local_model_backend.py", backend=backend, concurrency=1, instances={"conditions": ["a", "c"]}))
    assert {r.status for r in rows} == {"answered"}
    for row in rows:  # the model's point, from the images themselves
        point = (row.parse.selected_image, row.parse.x, row.parse.y)
        assert point == ((1, 40.0, 300.0) if row.condition == "a" else (None, 200.0, 150.0))
    # every second call finds the device busy: the first key answers at once, every later
    # key's first call is a busy one and its retry answers
    assert sorted(r.retries for r in rows) == [0, 1, 1, 1]
    assert result.summary.usage.retries == 3


def test_local_model_records_too_many_images_at_once_and_answers_the_rest(pipeline, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    backend = {"name": "local-brightest", "options": {"max_images": 2}}
    done = CliRunner().invoke(app, ["run", str(pipeline("local_model_backend.py", backend=backend, concurrency=1))])
    assert done.exit_code == 3, done.output  # the run finished; some keys are infra_error rows
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    failed = [r for r in rows if r.status == "infra_error"]
    assert {(r.condition, r.error_type, r.retries) for r in failed} == {("a", "too_many_images", 0), ("b", "too_many_images", 0)}
    assert "3 images, the model takes at most 2" in failed[0].error_message
    assert {r.status for r in rows if r.condition == "c"} == {"answered"}
    assert summary["rows"]["infra_error"] == 4 and summary["rows"]["answered"] == 2
