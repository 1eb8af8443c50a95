"""MMSI-Bench's circular split: each question asked four times with its options rotated, as the
set's authors build ``MMSI_Bench_Circular``, and scored as they score it (a question right only
when every copy is), beside the vanilla figure over each question's first copy.

The copies and every figure below were produced by RUNNING the upstream functions outside the
project on the same questions and replies: the authors' ``MMSIBenchCircular.load_data`` and
``evaluate`` (InternRobotics/MMSI-Bench@5de2f3d2eb0159dbcc76790074029aa400143603,
``vlmeval/dataset/mmsi_bench.py``) and VLMEvalKit's ``mcq_circular_eval`` with exact matching and
``report_acc`` (open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94,
``vlmeval/dataset/utils/multiple_choice.py``); never written by hand.
"""

from __future__ import annotations

import shutil
from fractions import Fraction
from pathlib import Path

import pytest
import yaml

from povagent.answers.choice_question import ChoiceQuestion
from povagent.config.pipeline import load_pipeline
from povagent.dataset.choice_sets import load_choice_set
from povagent.dataset.choice_sets.external import Item
from povagent.dataset.choice_sets.mmsi_circular_copies import rotated_copies, split_options
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline

from ..queued_runs import run_with_queued_replies
from .conftest import MMSI_ROWS, OFFLINE_PLUGIN, mmsi_rows, write_mmsi_parquet

PR_CAM_OBJ, PR_OBJ_OBJ, MEAS, MOTION_CAM, MSR = (
    "Positional Relationship (Cam.-Obj.)", "Positional Relationship (Obj.-Obj.)", "Attribute (Meas.)", "Motion (Cam.)", "MSR",
)  # fmt: skip

#: per question of the fixture, its four copies' replies: {} the copy's gold letter, {x} the letter
#: after it (a wrong one), {low} the gold in lower case
REPLIES = [
    ("``{}``", "``{}``", "``{}``", "``{}``"),
    ("{}", "{}", "{x}", "{}"),
    ("{x}", "{}", "{}", "{}"),
    ("A bike is near, so {}", "{}", "`{}`", "{}"),
    ("I cannot tell.", "{}", "{}", "{}"),
    ("The answer is {}.", "The answer is {}.", "The answer is {}.", "The answer is {}."),
    ("the answer is {low}", "{}", "{}", "{}"),
    ("Answer: {}", "Answer: {}", "Answer: {}", "Answer: {}"),
    ("{}\n{x}", "{}", "{}", "{}"),
    ("``{}``", "``{}``", "``{}``", "I think it is {x}"),
    ("<think>{x}</think>{}", "{}", "{}", "{}"),
]
#: the authors' evaluate on those replies: (Circular, Vanilla), overall and per question type
AUTHORS = {"overall": ("4/11", "6/11"), PR_CAM_OBJ: ("1/3", "2/3"), PR_OBJ_OBJ: ("1/2", "1/2"), MEAS: ("1/2", "1/2"),
           MOTION_CAM: ("1/2", "1/2"), MSR: ("0", "1/2")}  # fmt: skip
#: VLMEvalKit's mcq_circular_eval (exact matching) and report_acc on the same replies
VLMEVALKIT = {"overall": "3/11", PR_CAM_OBJ: "0", PR_OBJ_OBJ: "0", MEAS: "1", MOTION_CAM: "1/2", MSR: "0"}


def _replies(instances) -> list[str]:
    out = []
    for instance in instances:
        question, gold = int(instance.pair_id) % 1_000_000, instance.question.gold
        form = REPLIES[question][int(instance.pair_id) // 1_000_000]
        out.append(form.format(gold, x="ABCD"[("ABCD".index(gold) + 1) % 4], low=gold.lower()))
    return out


def _item(question: str, gold: str, id_: str = "7") -> Item:
    return Item(id_, ChoiceQuestion(question, (("A", ""), ("B", ""), ("C", ""), ("D", ""), ("E", "")), gold, category="X"), ())


@pytest.fixture
def circular_copy(tmp_path, mmsi_parquet):
    shutil.copy(mmsi_parquet, tmp_path / "MMSI_Bench.parquet")
    return tmp_path / "MMSI_Bench.parquet"


@pytest.fixture(scope="module")
def circular_run_made(tmp_path_factory, mmsi_parquet):
    """The circular run, made once a module (its tests only read it, or write beside it), by the
    ``queued`` backend on a plugin host of its own (as the ``queued_backend`` fixture makes one)."""
    folder = tmp_path_factory.mktemp("circular")
    copy = Path(shutil.copy(mmsi_parquet, folder / "MMSI_Bench.parquet"))
    plugin = Path(shutil.copy(OFFLINE_PLUGIN, folder / "offline_plugin.py")).resolve()
    instances = load_choice_set(copy, "mmsi-circular", cache_dir=folder / "c").instances()
    config = {"plugins": [str(plugin)], "dataset": {"path": str(copy), "format": "mmsi-circular"}, "backend": "queued",
              "strategy": "choice", "runs": 1, "concurrency": 1, "timeout": 5, "output": str(folder / "run")}  # fmt: skip
    (folder / "run.yaml").write_text(yaml.safe_dump(config))
    return run_with_queued_replies(folder / "run.yaml", _replies(instances))


@pytest.fixture
def circular_run(circular_run_made, queued_backend):
    """The module's circular run, read while a ``queued`` backend is registered (as when it ran)."""
    return circular_run_made


def _figures(summary, scorer: str, metric: str) -> dict[str, float]:
    metrics = summary.metrics[scorer]
    return {"overall": metrics.overall[metric].value, **{k: v[metric].value for k, v in (metrics.per_category or {}).items()}}


def _fractions(expected: dict, pick=lambda v: v) -> dict[str, float]:
    return {k: float(Fraction(pick(v))) for k, v in expected.items()}


def test_each_question_is_asked_four_times_its_options_rotated_as_the_authors_build_it(circular_copy, tmp_path):
    loaded = load_choice_set(circular_copy, "mmsi-circular", cache_dir=tmp_path / "c")
    first = [i for i in loaded.instances() if int(i.pair_id) % 1_000_000 == 0]
    assert loaded.problems == [] and len(loaded.instances()) == 4 * len(MMSI_ROWS)
    assert [(i.pair_id, i.question.question.splitlines()[-1], i.question.gold) for i in first] == [
        ("0", "Options: A: Front left, B: Front right, C: Back left, D: Back right", "A"),
        ("1000000", "Options: A: Front right, B: Back left, C: Back right, D: Front left", "D"),
        ("2000000", "Options: A: Back left, B: Back right, C: Front left, D: Front right", "C"),
        ("3000000", "Options: A: Back right, B: Front left, C: Front right, D: Back left", "B"),
    ]


def test_every_copy_asks_the_question_proper_and_shows_the_question_s_images(circular_copy, tmp_path):
    loaded = load_choice_set(circular_copy, "mmsi-circular", cache_dir=tmp_path / "c")
    copies = [i for i in loaded.instances() if int(i.pair_id) % 1_000_000 == 10]
    heads = {i.question.question.splitlines()[0] for i in copies}
    assert heads == {"The images are taken continuously from a first-person view. Question 10: where is it?"}
    assert len({i.frames for i in copies}) == 1 and len(copies[0].frames) == 3
    assert {(i.question.group, i.question.category, i.question.profile) for i in copies} == {("10", MSR, "mmsi")}
    assert [i.question.variant for i in copies] == ["ABCD", "BCDA", "CDAB", "DABC"]


def test_a_three_option_question_skips_the_missing_letter_as_the_authors_code_does():
    copies = rotated_copies(_item("Which way?\nOptions: A: left, B: right, C: ahead", "A"))
    assert [(c.id, c.question.question.splitlines()[1], c.question.gold) for c in copies] == [
        ("7", "Options: A: left, B: right, C: ahead", "A"),
        ("1000007", "Options: A: right, B: ahead, D: left", "D"),
        ("2000007", "Options: A: ahead, C: left, D: right", "C"),
        ("3000007", "Options: B: left, C: right, D: ahead", "B"),
    ]


def test_options_are_read_again_as_the_authors_circular_split_reads_them():
    # a space separates options too, and E is no label there: it stays in D's text
    assert split_options("How far?\nOptions: A: 1 m B: 2 m, C: 3 m, D: 4 m, E: 5 m") == (
        "How far?", {"A": "1 m", "B": "2 m", "C": "3 m", "D": "4 m, E: 5 m"})  # fmt: skip
    copies = rotated_copies(_item("How far?\nOptions: A: 1 m B: 2 m, C: 3 m, D: 4 m, E: 5 m", "B", "8"))
    assert copies[1].question.question == "How far?\nOptions: A: 2 m, B: 3 m, C: 4 m, E: 5 m, D: 1 m" and copies[1].question.gold == "A"


def test_a_gold_letter_no_option_carries_leaves_the_question_out_with_a_reason():
    assert "names none of the options" in rotated_copies(_item("Q?\nOptions: A: x, B: y", "C"))


@pytest.mark.parametrize("id_", ["q7", "1000000", "-3"])
def test_an_id_the_copies_cannot_be_numbered_from_is_refused(id_):
    assert "whole number below 1,000,000" in rotated_copies(_item("Q?\nOptions: A: x, B: y", "A", id_))


def test_a_row_left_out_is_named_and_the_rest_are_asked(tmp_path):
    rows = mmsi_rows()[:3]
    rows[1]["id"] = 2_000_001
    path = write_mmsi_parquet(tmp_path / "MMSI_Bench.parquet", rows)
    loaded = load_choice_set(path, "mmsi-circular", cache_dir=tmp_path / "c")
    assert [(p.json_path, "1,000,000" in p.message) for p in loaded.problems] == [("record 2000001.id", True)]
    assert len(loaded.instances()) == 8


def test_the_oracle_scores_every_question_under_the_circular_rule(tmp_path, circular_copy, offline_plugin_file):
    config = {"plugins": [str(offline_plugin_file)], "dataset": {"path": str(circular_copy), "format": "mmsi-circular"}, "backend": "oracle",
              "strategy": "choice", "runs": 1, "concurrency": 2, "timeout": 5, "output": str(tmp_path / "oracle")}  # fmt: skip
    (tmp_path / "oracle.yaml").write_text(yaml.safe_dump(config))
    result = run_pipeline(load_pipeline(tmp_path / "oracle.yaml"))
    assert result.n_total == 4 * len(MMSI_ROWS)
    assert set(_figures(result.summary, "choice-mmsi-circular", "circular_accuracy").values()) == {1.0}


def test_a_circular_run_is_read_and_scored_by_the_set_s_own_circular_rule(circular_run):
    config = yaml.safe_load((circular_run.run_dir / "config.yaml").read_text())
    assert config["parser"]["name"] == "mmsi-official" and "choice-mmsi-circular" in [s["name"] for s in config["scorers"]]


def test_circular_and_vanilla_accuracies_are_the_authors_evaluate_s(circular_run):
    summary = circular_run.summary
    assert _figures(summary, "choice-mmsi-circular", "circular_accuracy") == pytest.approx(_fractions(AUTHORS, lambda v: v[0]), abs=1e-12)
    assert _figures(summary, "choice-mmsi-circular", "vanilla_accuracy") == pytest.approx(_fractions(AUTHORS, lambda v: v[1]), abs=1e-12)


def test_the_circular_accuracy_counts_questions_and_the_vanilla_one_first_copies(circular_run):
    overall = circular_run.summary.metrics["choice-mmsi-circular"].overall
    assert (overall["circular_accuracy"].n, overall["vanilla_accuracy"].n, overall["response_rate"].n) == (11, 11, 44)


def test_each_copy_s_row_names_its_question_and_option_order(circular_run):
    rows = read_rows(circular_run.run_dir / "results.jsonl")
    fields = rows[5].scores["choice-mmsi-circular"]
    assert (rows[5].pair_id, fields["question_group"], fields["variant"]) == ("1000001", "1", "BCDA")


def test_read_with_vlmevalkit_s_exact_matching_the_run_gives_vlmevalkit_s_circular_figures(circular_run):
    rescored = rescore_run(circular_run.run_dir, "vlmevalkit-exact")
    assert _figures(rescored.summary, "choice-mmsi-circular", "circular_accuracy") == pytest.approx(_fractions(VLMEVALKIT), abs=1e-12)


def test_the_report_gives_the_run_s_circular_and_vanilla_figures(circular_run, tmp_path):
    import json

    from povagent.report.build import write_report

    write_report(circular_run.run_dir, tmp_path / "report", gallery=False, n_boot=200)
    (system,) = json.loads((tmp_path / "report" / "summary.json").read_text())["metrics"]["choice-mmsi-circular"].values()
    cells = {"overall": system["overall"], **system["per_category"]}
    assert {k: c["circular_accuracy"]["value"] for k, c in cells.items()} == pytest.approx(_fractions(AUTHORS, lambda v: v[0]), abs=1e-12)
    assert {k: c["vanilla_accuracy"]["value"] for k, c in cells.items()} == pytest.approx(_fractions(AUTHORS, lambda v: v[1]), abs=1e-12)
