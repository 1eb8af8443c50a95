"""``povagent rescore-log``: the table of rules, their numbers and disagreements, or the JSON object."""

from __future__ import annotations

import gzip
import json
import textwrap
from pathlib import Path

from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()
FIXTURES = Path(__file__).resolve().parent.parent / "fixtures" / "harness_logs"


def lmms_log(tmp_path: Path, extra: str = "") -> Path:
    """The ViewSpatial-Bench lmms-eval log of ``tests/fixtures/harness_logs`` (300 questions), unpacked."""
    path = tmp_path / "20261207_samples_viewspatial.jsonl"
    path.write_bytes(gzip.decompress((FIXTURES / "viewspatial_samples.jsonl.gz").read_bytes()) + extra.encode())
    return path


def test_json_is_the_object_the_issue_names(tmp_path):
    result = runner.invoke(app, ["rescore-log", str(lmms_log(tmp_path)), "--harness", "lmms-eval", "--set", "viewspatial", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert (out["set"], out["items"]) == ("viewspatial", 300)
    assert [r["rule"] for r in out["rules"]] == ["viewspatial-official", "viewspatial", "vlmevalkit-spatial"]
    for rule in out["rules"]:
        assert {"rule", "source", "overall", "per_category"} <= rule.keys()
        assert "@" in rule["source"] and len(rule["per_category"]) == 5
        assert rule["overall_ci"][0] <= rule["overall"] <= rule["overall_ci"][1]
    assert out["rules"][1]["overall"] == 133 / 300  # lmms-eval's viewspatial_aggregate_results on these replies


def test_the_table_names_each_rule_what_it_read_its_numbers_and_the_disagreements(tmp_path):
    result = runner.invoke(
        app, ["rescore-log", str(lmms_log(tmp_path)), "--harness", "lmms-eval", "--set", "viewspatial", "--show", "5"], env={"COLUMNS": "200"}
    )
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "300 replies of viewspatial logged by lmms-eval, read by 3 rules" in out
    assert (
        "viewspatial-official (official): ViewSpatial-Bench's rule, ZJU-REAL/ViewSpatial-Bench@2e85a5e41a29e7919b1d326d8aba316661579983; reads resps as written"
        in out
    )
    assert "viewspatial: lmms-eval's rule" in out and "reads resps, then lmms-eval's reasoning-tag strip" in out
    assert "44.3% [" in out  # lmms-eval's 133/300 with its CI
    assert "The rules read 41 of 300 replies differently (first 5" in out
    assert "44 of 300 replies were changed by the harness's own filter" in out


def test_a_bad_record_is_named_on_stderr_and_the_rest_scored(tmp_path):
    path = lmms_log(tmp_path, '{"doc_id": "x", "target": "B", "filtered_resps": ["B"], "resps": 3}\n')
    result = runner.invoke(app, ["rescore-log", str(path), "--harness", "lmms-eval", "--set", "viewspatial"])
    assert result.exit_code == 0, result.output
    assert f"bad record: {path}: line 301.resps: the reply must be text" in result.stderr
    assert "1 record(s) left out (named above), 300 scored" in result.stderr


def test_an_unknown_harness_or_set_is_one_line(tmp_path):
    path = lmms_log(tmp_path)
    result = runner.invoke(app, ["rescore-log", str(path), "--harness", "opencompass", "--set", "viewspatial"])
    assert result.exit_code != 0
    assert "unknown harness 'opencompass' (known: lmms-eval, vlmevalkit)" in str(result.exception)


def test_a_rule_from_a_plugin_module_is_scored_beside_the_others(tmp_path):
    module = tmp_path / "first_letter_rule.py"
    module.write_text(textwrap.dedent('''
        from povagent import hookimpl
        from povagent_plugins.parsers.mcq.rule import RuleParser

        class FirstLetter(RuleParser):
            source = "example/harness@" + "0" * 40
            harness = "example-harness"
            harness_sets = (("viewspatial", "choice"),)

            def label(self, text, spec):
                return text[:1] or None

        @hookimpl
        def register_parsers(register):
            register("first-letter", FirstLetter, description="the reply's first character")
    '''))
    result = runner.invoke(app, ["rescore-log", str(lmms_log(tmp_path)), "--harness", "lmms-eval", "--set", "viewspatial", "--json", "--plugin", str(module)])
    assert result.exit_code == 0, result.output
    rules = {r["rule"]: r for r in json.loads(result.stdout)["rules"]}
    assert rules["first-letter"]["harness"] == "example-harness" and rules["first-letter"]["overall"] is not None


def test_the_json_validates_against_the_shipped_schema(tmp_path):
    from importlib import resources

    from jsonschema import Draft202012Validator

    result = runner.invoke(app, ["rescore-log", str(lmms_log(tmp_path)), "--harness", "lmms-eval", "--set", "viewspatial", "--json"])
    schema = json.loads(resources.files("povagent").joinpath("schemas", "output_rescore-log.schema.json").read_text(encoding="utf-8"))
    assert list(Draft202012Validator(schema).iter_errors(json.loads(result.stdout))) == []


def test_a_log_with_numerical_questions_says_a_rule_reads_an_answer_and_shows_numbers(tmp_path):
    path = tmp_path / "20261207_samples_vsibench.jsonl"
    path.write_bytes(gzip.decompress((FIXTURES / "vsibench_samples.jsonl.gz").read_bytes()))
    result = runner.invoke(app, ["rescore-log", str(path), "--harness", "lmms-eval", "--set", "vsibench", "--show", "40"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "reads an answer (an option or a number) in 156 of 230 replies" in result.stdout
    assert "(no answer read = 0)" in " ".join(result.stdout.split())  # the table's caption, wrapped to the console
    assert "About 93 meters." in result.stdout and "│ 93 " in result.stdout  # lmms-eval's extract_number; the set's first word reads none


def test_a_vlmevalkit_vsibench_file_gives_json_with_each_rule_beside_the_sets_that_validates(tmp_path):
    from importlib import resources

    from jsonschema import Draft202012Validator

    path = tmp_path / "Qwen2.5-VL-7B_VSI-Bench.xlsx"
    path.write_bytes((FIXTURES / "VSI-Bench_preds.xlsx").read_bytes())
    result = runner.invoke(app, ["rescore-log", str(path), "--harness", "vlmevalkit", "--set", "vsibench", "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    schema = json.loads(resources.files("povagent").joinpath("schemas", "output_rescore-log.schema.json").read_text(encoding="utf-8"))
    assert list(Draft202012Validator(schema).iter_errors(out)) == []
    assert (out["items"], out["numerical"]) == (320, 131)
    assert [(r["rule"], r["official"], r["scorer"]) for r in out["rules"]] == [
        ("vsibench", True, "vsibench"), ("vlmevalkit-vsibench", False, "vsibench-vlmevalkit"), ("vsibench-lmms", False, "vsibench")]  # fmt: skip
    assert round(100 * out["rules"][1]["overall"], 3) == 47.910  # VsiBench.evaluate's own table on this file
    assert "VLMEvalKit's load" in out["rules"][1]["reads"]
