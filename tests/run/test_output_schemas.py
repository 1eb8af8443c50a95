"""The JSON Schemas of what povagent writes: shipped, printed by ``povagent schema``, and met by
the files a real sweep writes."""

from __future__ import annotations

import ast
import json
from importlib import resources
from pathlib import Path

import pytest
import yaml
from jsonschema import Draft202012Validator
from typer.testing import CliRunner

import povagent.results.transcript as transcript_module
import povagent.run.solve_key as solve_key_module
from povagent.cli import app
from povagent.results.rows import ExchangeRecord, ResultRow
from povagent.run.output_schemas import OUTPUT_MODELS, output_schema_text
from povagent.run.summary_model import RunSummary
from povagent.run.sweep import run_sweep
from povagent.run.sweep_index import SweepIndex
from povagent.testing.pytest_plugin import write_release


def shipped(name: str) -> str:
    return resources.files("povagent").joinpath("schemas", f"output_{name}.schema.json").read_text(encoding="utf-8")


def validator(name: str) -> Draft202012Validator:
    return Draft202012Validator(json.loads(shipped(name)))


@pytest.mark.parametrize("name", list(OUTPUT_MODELS))
def test_the_shipped_schema_is_what_the_model_generates(name):
    # python -m povagent.run.output_schemas rewrites them
    assert shipped(name) == output_schema_text(name)


@pytest.mark.parametrize("name", list(OUTPUT_MODELS))
def test_povagent_schema_prints_the_shipped_schema(name):
    result = CliRunner().invoke(app, ["schema", name])
    assert result.exit_code == 0, result.output
    assert result.output == shipped(name)


def test_povagent_schema_refuses_an_unknown_name_naming_the_known_ones():
    result = CliRunner().invoke(app, ["schema", "summaries"])
    assert result.exit_code != 0
    assert "summary, row, sweep, export, rescore-log" in str(result.exception)


@pytest.fixture(scope="module")
def two_run_sweep(tmp_path_factory) -> Path:
    """Two baselines, two runs each, a lenient parser and the diagnostics: every section of a
    summary (per-run means, pooled, official reading, diagnostics) is written."""
    root = tmp_path_factory.mktemp("schemas")
    release = write_release(root / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)
    base = {
        "dataset": {"path": str(release)},
        "backend": {"name": "center"},
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official", "diagnose"],
        "runs": 2,
        "concurrency": 4,
        "output": "ignored-by-sweeps",
    }
    (root / "base.yaml").write_text(yaml.safe_dump(base))
    sweep = root / "sweep.yaml"
    sweep.write_text(
        yaml.safe_dump({"base": "base.yaml", "output": str(root / "sweep"), "axes": {"backend": ["center", {"name": "random", "options": {"seed": 1}}]}})
    )
    return run_sweep(sweep, quiet=True).output


def test_every_summary_a_sweep_writes_meets_the_summary_schema(two_run_sweep):
    summaries = sorted(two_run_sweep.glob("*/summary.json"))
    assert len(summaries) == 2
    for path in summaries:
        data = json.loads(path.read_text())
        assert list(validator("summary").iter_errors(data)) == []
        typed = RunSummary.model_validate(data)
        assert typed.pooled is not None and typed.official_parse is not None and typed.diagnostics is not None


def test_every_row_a_sweep_writes_meets_the_row_schema(two_run_sweep):
    rows = [json.loads(line) for path in sorted(two_run_sweep.glob("*/results.jsonl")) for line in path.read_text().splitlines()]
    assert rows
    check = validator("row")
    for row in rows:
        assert list(check.iter_errors(row)) == [], row["key"]


def test_the_sweep_index_meets_the_sweep_schema(two_run_sweep):
    data = json.loads((two_run_sweep / "sweep.json").read_text())
    assert list(validator("sweep").iter_errors(data)) == []
    assert [c.status for c in SweepIndex.model_validate(data).cells] == ["done", "done"]


def test_a_summary_with_an_unknown_section_fails_its_schema(two_run_sweep):
    data = json.loads(next(two_run_sweep.glob("*/summary.json")).read_text())
    assert list(validator("summary").iter_errors({**data, "surprise": 1}))


def _construct_keywords(model: str) -> set[str]:
    """The keywords of the ``construct(<model>, ...)`` call of the module that builds it
    (the solve step a row, the row's transcript an exchange)."""
    module = transcript_module if model == "ExchangeRecord" else solve_key_module
    tree = ast.parse((Path(module.__file__)).read_text(encoding="utf-8"))
    calls = [
        node for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "construct"
        and node.args and isinstance(node.args[0], ast.Name) and node.args[0].id == model
    ]  # fmt: skip
    assert len(calls) == 1, f"expected one construct({model}, ...) call in {module.__name__}"
    return {k.arg for k in calls[0].keywords if k.arg is not None}


@pytest.mark.parametrize("model", [ResultRow, ExchangeRecord])
def test_the_runner_builds_a_row_without_validation_only_by_naming_every_field(model):
    # construct skips validation: a field left out would quietly take its default (and the
    # model be built the slow way, by model_construct)
    assert _construct_keywords(model.__name__) == set(model.model_fields)


def test_every_row_a_sweep_writes_reads_back_to_the_same_json(two_run_sweep):
    for path in sorted(two_run_sweep.glob("*/results.jsonl")):
        for line in path.read_text().splitlines():
            assert ResultRow.model_validate_json(line).model_dump(mode="json") == json.loads(line)


def test_a_rescored_summary_meets_the_summary_schema(two_run_sweep):
    from povagent.run.rescore import rescore_run

    result = rescore_run(two_run_sweep / "center", "official")
    data = json.loads((result.out_dir / "summary.json").read_text())
    assert list(validator("summary").iter_errors(data)) == []
    assert RunSummary.model_validate(data).parse_status is not None


def _objects(schema: dict) -> list[tuple[str, dict]]:
    return [("(root)", schema), *schema.get("$defs", {}).items()]


@pytest.mark.parametrize("name", list(OUTPUT_MODELS))
def test_every_object_a_shipped_schema_describes_refuses_fields_it_does_not_list(name):
    open_objects = [where for where, d in _objects(json.loads(shipped(name))) if "properties" in d and d.get("additionalProperties") is not False]
    assert open_objects == []


def test_a_row_holding_a_misspelled_field_fails_the_output_check_before_it_is_written(two_run_sweep, tmp_path, monkeypatch):
    from povagent.results.output_check import ENV, OutputSchemaError
    from povagent.results.rows import ResultsWriter

    monkeypatch.setenv(ENV, "1")
    line = next(two_run_sweep.glob("*/results.jsonl")).read_text().splitlines()[0]
    row = ResultRow.model_validate_json(line)
    misspelled = ResultRow.model_construct(**{**dict(row), "lable": "fine-tuned"})  # the maintainer meant "label"
    with pytest.raises(OutputSchemaError, match="lable"), ResultsWriter(tmp_path / "results.jsonl") as writer:
        writer.write(misspelled)
    assert (tmp_path / "results.jsonl").read_text() == ""


def test_a_row_another_version_wrote_with_a_field_unknown_here_still_reads(two_run_sweep):
    line = next(two_run_sweep.glob("*/results.jsonl")).read_text().splitlines()[0]
    row = ResultRow.model_validate_json(json.dumps({**json.loads(line), "from_a_later_version": 1}))
    assert row.key == json.loads(line)["key"]
