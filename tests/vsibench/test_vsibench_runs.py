"""A VSI-Bench pipeline runs end to end from its format alone: the set's frames, its wording,
its own first-word rule and scorer; the oracle scores every question, and always answering "A"
scores what the per-type rule says by hand."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.dataset.formats import registered_format
from povagent.plugins import build_plugin_host
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

from .conftest import RECORDS


@pytest.fixture
def vsibench_pipeline(tmp_path, vsibench_folder, offline_plugin_file):
    def make(backend: str = "oracle", reply: str | None = None, file: str = "test.parquet", **more) -> object:
        data = {
            "plugins": [str(offline_plugin_file)],
            "dataset": {"path": str(vsibench_folder / file), "format": "vsibench", "options": {"frames": 3}},
            "backend": {"name": backend, **({"options": {"reply": reply}} if reply is not None else {})},
            "runs": 1,
            "concurrency": 2,
            "timeout": 5,
            "output": str(tmp_path / f"run-{backend}-{reply}"),
            **more,
        }
        path = tmp_path / f"{backend}-{reply}.yaml"
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return load_pipeline(path)

    return make


def test_the_format_alone_chooses_the_strategy_the_sets_rule_and_its_scorer(vsibench_pipeline):
    config = vsibench_pipeline()
    assert (config.strategy.name, config.parser.name, [s.name for s in config.scorers]) == ("choice-or-number", "vsibench", ["vsibench"])


def test_the_oracle_scores_every_question(vsibench_pipeline):
    result = run_pipeline(vsibench_pipeline())
    metrics = result.summary.metrics["vsibench"]
    assert result.n_total == len(RECORDS)
    assert metrics.overall["score"].value == 1.0 and metrics.overall["response_rate"].value == 1.0
    assert (metrics.overall["unscorable"].value, metrics.overall["unscorable"].n) == (0.0, len(RECORDS))  # the summary counts them
    assert {k: v["score"].value for k, v in metrics.per_category.items()} == {r["question_type"]: 1.0 for r in RECORDS}


def test_always_answering_a_scores_the_gold_a_questions_and_no_number(vsibench_pipeline):
    result = run_pipeline(vsibench_pipeline(backend="test-center", reply="A"))
    metrics = result.summary.metrics["vsibench"]
    # gold A: ids 5 (easy) and 8 (route planning) of 6 choice questions; "A" is no number (scored 0)
    per_type = {k: v["score"].value for k, v in metrics.per_category.items()}
    assert per_type["object_rel_direction_easy"] == 1.0 and per_type["route_planning"] == 1.0
    assert per_type["object_counting"] == 0.0 and per_type["object_rel_distance"] == 0.0
    # the set's overall: the 8 type scores' mean, direction = (easy 1 + medium 0 + hard 0) / 3, route planning 1
    assert metrics.overall["score"].value == pytest.approx((1 / 3 + 1) / 8)
    assert metrics.overall["response_rate"].value == pytest.approx(6 / 11)


def test_rows_record_the_typed_answer_and_the_question_type(vsibench_pipeline):
    result = run_pipeline(vsibench_pipeline(backend="test-center", reply="A"))
    rows = {r.pair_id: r for r in read_rows(result.run_dir / "results.jsonl")}
    assert rows["0"].status == "parse_error" and rows["0"].category == "object_counting"
    assert rows["5"].prediction.answer_type == "choice-or-number" and rows["5"].prediction.value == {"choice": "A"}
    assert rows["5"].category == "object_rel_direction_easy"


def test_the_request_shows_the_frames_then_the_sets_wording(vsibench_folder):
    from povagent.dataset.choice_sets.vsibench_set import load_vsibench
    from povagent.exchange.images import ImageStore
    from povagent.exchange.messages import ImagePart, TextPart
    from povagent_plugins.strategies.choice_or_number import ChoiceOrNumberStrategy

    loaded = load_vsibench(vsibench_folder / "test.jsonl", frames=3, cache_dir=vsibench_folder / "cache")
    strategy = ChoiceOrNumberStrategy()
    counting = strategy.build(loaded.instance("vsibench/0"), ImageStore())
    parts = counting.messages[0].parts
    assert [type(p) for p in parts] == [ImagePart, ImagePart, ImagePart, TextPart]
    assert parts[-1].text == (
        "These are frames of a video.\nHow many chair(s) are in this room?\nPlease answer the question using a single word or phrase."
    )
    assert counting.answer.required_keys == ("number",) and counting.answer.choices == ()
    direction = strategy.build(loaded.instance("vsibench/5"), ImageStore())
    assert direction.messages[0].parts[-1].text == (
        "These are frames of a video.\nIf I am standing by the sofa and facing the tv, is the lamp to my left or the right?\n"
        "Options:\nA. left\nB. right\nAnswer with the option's letter from the given choices directly."
    )
    assert direction.answer.choices == (("A", "left"), ("B", "right"))


def test_the_format_is_registered_with_its_official_rule():
    fmt = registered_format(build_plugin_host(), "vsibench")
    assert (fmt.answer_type, fmt.official_parser, fmt.official_scorer, fmt.option_names) == (
        "choice-or-number",
        "vsibench",
        "vsibench",
        ("frames", "cache_dir"),
    )
    assert fmt.prompt_profile.text.__name__ == "vsibench_text"


def test_an_unknown_dataset_option_is_refused(vsibench_pipeline):
    from povagent.errors import ConfigError, DatasetError

    with pytest.raises((ConfigError, DatasetError), match="colour"):
        run_pipeline(vsibench_pipeline(**{"dataset": {"path": "x", "format": "vsibench", "options": {"colour": 1}}}))


def test_the_sets_overall_comes_from_the_summarys_per_type_scores(vsibench_pipeline):
    import json

    from povagent_plugins.scorers.vsibench_scorer import official_overall

    result = run_pipeline(vsibench_pipeline(backend="test-center", reply="A"))
    summary = json.loads((result.run_dir / "summary.json").read_text())
    per_type = {k: v["score"]["value"] for k, v in summary["metrics"]["vsibench"]["per_category"].items()}
    table = official_overall(per_type)
    # by hand: direction = (easy 1 + medium 0 + hard 0) / 3; route planning 1; the other six types 0
    assert table["object_rel_direction"] == pytest.approx(1 / 3)
    assert table["overall"] == pytest.approx((1 / 3 + 1) / 8)
    assert summary["metrics"]["vsibench"]["overall"]["score"]["value"] == pytest.approx(table["overall"])


def test_the_report_of_a_run_shows_every_question_numerical_ones_too(vsibench_pipeline, tmp_path):
    from povagent.report.build import write_report

    result = run_pipeline(vsibench_pipeline())
    write_report(result.run_dir, tmp_path / "report")
    answers = "".join(p.read_text() for p in (tmp_path / "report" / "answers").glob("*.js"))
    # a numerical card carries the set's wording and the number answered, a choice card its options
    assert "How many chair(s) are in this room?" in answers and '"a":"4.0"' in answers
    assert (tmp_path / "report" / "report.html").is_file()


def test_the_how_to_pages_row_is_the_formats_own():
    from pathlib import Path

    fmt = registered_format(build_plugin_host(), "vsibench")
    page = Path(__file__).resolve().parents[2] / "docs" / fmt.docs_row.how_to
    row = f"| {fmt.docs_row.name} | {fmt.docs_row.where} | {fmt.licence} | {fmt.docs_row.path} | `{fmt.key}` |"
    assert row in page.read_text(encoding="utf-8").splitlines()


def test_rescoring_a_run_under_lmms_evals_reading_reads_no_video(vsibench_pipeline, vsibench_folder):
    from povagent.run.rescore import rescore_run

    result = run_pipeline(vsibench_pipeline(backend="test-center", reply="about 2"))
    assert result.summary.metrics["vsibench"].overall["score"].value == 0.0  # officially "about" is no number
    for video in vsibench_folder.rglob("*.mp4"):
        video.unlink()  # rescoring needs the gold answers, not the frames
    again = rescore_run(result.run_dir, "vsibench-lmms").summary.metrics["vsibench"]
    # lmms-eval reads 2: counting golds 4 and 2 -> MRA 0.1 and 1 (type 0.55); distance 1.8 -> 0.8;
    # size 203 and room 22.4 -> 0; the six choice types 0 -> (0.55 + 0.8) / 8
    assert again.per_category["object_counting"]["score"].value == pytest.approx(0.55)
    assert again.overall["score"].value == pytest.approx((0.55 + 0.8) / 8)
    assert rescore_run(result.run_dir, "vsibench").summary.metrics["vsibench"].overall["score"].value == 0.0
