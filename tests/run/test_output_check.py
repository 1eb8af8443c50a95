"""Every file with a shipped schema is checked against it as povagent writes it, while tests run:
a writer that drifts from the schema fails the test that made it write, naming the file."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results import rows
from povagent.results.output_check import ENV, OutputSchemaError, checking, schema_errors
from povagent.results.rows import ResultRow, ResultsWriter, RowStatus
from povagent.run.runner import PipelineRun, run_pipeline
from povagent.run.sweep import run_sweep
from povagent.train.export_folder import export_folder


def a_row() -> ResultRow:
    return ResultRow(key="h/0/left/a#0", instance_id="h/0/left/a", house_id="h", pair_id="0", direction="left",
                     condition="a", status=RowStatus.ANSWERED, parser="json")  # fmt: skip


def test_the_suite_checks_what_povagent_writes_here_and_in_the_processes_it_starts():
    assert checking()
    code = "from povagent.results.output_check import checking; print(checking())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True)
    assert out.stdout.strip() == "True"


def test_a_row_that_misses_the_row_schema_is_refused_naming_the_file_and_nothing_is_written(tmp_path, monkeypatch):
    drifted = a_row().model_dump_json(exclude_none=False).replace('"answered"', '"exploded"')
    monkeypatch.setattr(rows, "row_json", lambda row: drifted)
    path = tmp_path / "results.jsonl"
    with ResultsWriter(path) as writer, pytest.raises(OutputSchemaError) as caught:
        writer.write(a_row())
    assert str(path) in str(caught.value) and "$.status: 'exploded'" in str(caught.value)
    assert path.read_text() == ""


def test_users_runs_do_not_pay_for_the_check(tmp_path, monkeypatch):
    monkeypatch.delenv(ENV)
    drifted = a_row().model_dump_json(exclude_none=False).replace('"answered"', '"exploded"')
    monkeypatch.setattr(rows, "row_json", lambda row: drifted)
    with ResultsWriter(tmp_path / "results.jsonl") as writer:
        writer.write(a_row())
    assert json.loads((tmp_path / "results.jsonl").read_text())["status"] == "exploded"


def test_a_summary_the_schema_refuses_is_not_written_even_where_pydantic_would_coerce_it(write_pipeline, monkeypatch):
    summarize = PipelineRun.summarize

    def drifted(self, *args):
        summary = summarize(self, *args)
        summary["rows"]["total"] = str(summary["rows"]["total"])  # pydantic's lax mode reads "12" as 12
        return summary

    monkeypatch.setattr(PipelineRun, "summarize", drifted)
    config = load_pipeline(write_pipeline())
    with pytest.raises(OutputSchemaError, match=r"summary\.json.*\$\.rows\.total"):
        run_pipeline(config)
    assert not (config.output / "summary.json").exists()
    assert (config.output / "results.jsonl").read_text().count("\n") == 12  # the rows are kept


def test_a_summary_that_is_not_a_run_summary_is_refused_outside_tests_too(write_pipeline, monkeypatch):
    monkeypatch.delenv(ENV)
    summarize = PipelineRun.summarize
    monkeypatch.setattr(PipelineRun, "summarize", lambda self, *a: {**summarize(self, *a), "surprise": 1})
    config = load_pipeline(write_pipeline())
    with pytest.raises(ValueError, match="surprise"):
        run_pipeline(config)
    assert not (config.output / "summary.json").exists()


def test_a_sweep_index_that_misses_its_schema_is_refused_naming_sweep_json(tmp_path, write_pipeline, monkeypatch):
    import povagent.run.sweep as sweep_module

    cell_status = sweep_module.cell_status
    monkeypatch.setattr(sweep_module, "cell_status", lambda res: {**cell_status(res), "status": "finished"})
    base = yaml.safe_load(write_pipeline().read_text())
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": base, "output": str(tmp_path / "sweep"), "axes": {"runs": [1]}}))
    with pytest.raises(OutputSchemaError, match=r"sweep\.json.*status"):
        run_sweep(sweep, quiet=True)


def test_an_export_manifest_that_misses_its_schema_is_refused_and_not_written(tmp_path):
    out = tmp_path / "export"
    with pytest.raises(OutputSchemaError, match=r"export\.json"), export_folder(out, {"version": 3, "options": {}, "surprise": 1}):
        pass
    assert not (out / "export.json").exists()


def test_schema_errors_name_the_json_path(tmp_path):
    row = json.loads(a_row().model_dump_json())
    assert schema_errors("row", row) == []
    errors = schema_errors("row", {**row, "status": 3})
    assert errors and errors[0].startswith("$.status:")


def test_a_prediction_value_that_misses_its_answer_types_schema_is_refused_naming_the_instance(mini_root):
    from povagent.answers.spec import ParsedAnswer, ParseStatus
    from povagent.answers.types import AnswerType
    from povagent.dataset.loader import load_dataset
    from povagent.run.score_step import prediction_of
    from povagent_plugins.answers.point import POINT

    instance = next(iter(load_dataset(mini_root, check_images=False).instances()))
    parse = ParsedAnswer(status=ParseStatus.OK, selected_image=0, x=10.0, y=20.0)
    drifted = AnswerType(name="drifted", description="", value_schema=POINT.value_schema, gold=POINT.gold, show=POINT.show,
                         value_of=lambda p: {"selected_image": p.selected_image, "x": str(p.x), "y": p.y})  # fmt: skip
    assert prediction_of(instance, parse, POINT).value == {"selected_image": 0, "x": 10.0, "y": 20.0}
    with pytest.raises(OutputSchemaError) as caught:
        prediction_of(instance, parse, drifted)
    assert instance.id in str(caught.value) and "$.prediction.value.x: '10.0' is not of type 'number'" in str(caught.value)
