"""A fourth choice set is one plugin module: ``examples/dataset_format/povagent_tinyspatial.py``,
installed here as a distribution would be (a ``*.dist-info`` with its ``povagent`` entry point on
``sys.path``, nothing in ``povagent/`` or ``plugins/`` edited), is a registered format with its
own reader, rule and prompt, and a small set of it is read through the normal paths: ``povagent
validate --format``, and a pipeline naming only the set and a backend, run to its scores."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
import yaml
from PIL import Image
from typer.testing import CliRunner

from povagent import plugins
from povagent.cli import app
from povagent.config.pipeline import load_pipeline
from povagent.dataset.formats import missing_rules, registered_format
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

MODULE = Path(__file__).parents[2] / "examples" / "dataset_format" / "povagent_tinyspatial.py"
PAGE = Path(__file__).parents[2] / "docs" / "how-to" / "extend-povagent.md"
RECORDS = [
    {"id": "q1", "images": ["img/kitchen.png"], "question": "Seen from the chair, where is the mug?", "options": ["left", "right"],
     "answer": "B", "category": "relative"},
    {"id": "q2", "images": ["img/kitchen.png", "img/hall.png"], "question": "From the door, is the lamp left or right of the sofa?",
     "options": ["left", "right", "behind"], "answer": "A", "category": "relative"},
    {"id": "q3", "images": ["img/hall.png"], "question": "Facing the window, where is the bed?", "options": ["left", "right"],
     "answer": "B", "category": "absolute"},
]  # fmt: skip
REPLY = "The mug stands by the kettle.\nAnswer: b"


@pytest.fixture
def tinyspatial(tmp_path, monkeypatch):
    """The module installed by entry point only, and a fresh plugin host that discovered it."""
    site = tmp_path / "site-packages"
    info = site / "povagent_tinyspatial-0.1.dist-info"
    info.mkdir(parents=True)
    shutil.copy(MODULE, site / MODULE.name)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: povagent-tinyspatial\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[povagent]\ntinyspatial = povagent_tinyspatial\n")
    monkeypatch.syspath_prepend(str(site))
    host = plugins.build_plugin_host()
    monkeypatch.setattr(plugins, "_OVERRIDE", host)
    yield host
    sys.modules.pop("povagent_tinyspatial", None)


@pytest.fixture
def set_file(tmp_path) -> Path:
    """Three records of the set in its published JSONL, beside the two images they show."""
    folder = tmp_path / "tinyspatial"
    (folder / "img").mkdir(parents=True)
    for shade, name in enumerate(("kitchen", "hall")):
        Image.new("RGB", (16, 12), (60 * shade, 90, 30)).save(folder / "img" / f"{name}.png")
    file = folder / "tinyspatial.jsonl"
    file.write_text("".join(json.dumps(r) + "\n" for r in RECORDS))
    return file


def test_the_entry_point_alone_registers_the_format_and_its_rule(tinyspatial):
    fmt = registered_format(tinyspatial, "tinyspatial")
    assert tinyspatial.entry("format", "tinyspatial").source == "entry point tinyspatial = povagent_tinyspatial from povagent-tinyspatial 0.1"
    assert (fmt.official_parser, fmt.official_scorer, fmt.answer_type) == ("tinyspatial-official", "choice", "choice")
    assert missing_rules(tinyspatial) == []


def test_povagent_plugins_lists_the_format(tinyspatial):
    listing = json.loads(CliRunner().invoke(app, ["plugins", "--json"]).stdout)
    (row,) = [e for e in listing["format"] if e["name"] == "tinyspatial"]
    assert row["upstream"] == "example/TinySpatial@0123456789abcdef0123456789abcdef01234567" and row["official_parser"] == "tinyspatial-official"


def test_validate_reads_the_set_by_its_format_and_names_a_bad_record(tinyspatial, set_file):
    assert "tinyspatial" in CliRunner().invoke(app, ["validate", "--help"]).stdout
    assert CliRunner().invoke(app, ["validate", str(set_file), "--format", "tinyspatial"]).exit_code == 0
    with set_file.open("a") as f:
        f.write(json.dumps({**RECORDS[0], "id": "q4", "answer": "C"}) + "\n")
    result = CliRunner().invoke(app, ["validate", str(set_file), "--format", "tinyspatial"])
    assert result.exit_code == 1
    assert result.stdout.splitlines() == [f"{set_file}: line 4.answer: the gold label 'C' is not among the options (A, B)"]


def test_a_pipeline_naming_the_set_gets_its_rule_prompt_and_scores(tinyspatial, set_file, tmp_path, offline_plugin_file):
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({
        "plugins": [str(offline_plugin_file)],
        "dataset": {"path": str(set_file), "format": "tinyspatial"},
        "backend": {"name": "test-center", "options": {"reply": REPLY}},
        "output": str(tmp_path / "run"),
    }))  # fmt: skip
    config = load_pipeline(pipeline)
    assert (config.strategy.name, config.parser.name if config.parser else None) == ("choice", "tinyspatial-official")
    assert [s.name for s in config.scorers] == ["choice"]
    result = run_pipeline(config)
    # the reply reads B (its last "Answer: X", any case): right for q1 and q3, wrong for q2
    assert result.summary.metrics["choice"].overall["accuracy"].value == pytest.approx(2 / 3)
    rows = sorted(read_rows(tmp_path / "run" / "results.jsonl"), key=lambda r: r.instance_id)
    assert [r.parse.choice for r in rows] == ["B", "B", "B"]
    assert "End your reply with 'Answer: X', X the option's letter." in json.dumps(rows[0].model_dump(mode="json")["exchanges"][0])


def test_the_how_to_shows_the_module_in_full():
    assert f"```python\n{MODULE.read_text(encoding='utf-8').rstrip()}\n```" in PAGE.read_text(encoding="utf-8")
