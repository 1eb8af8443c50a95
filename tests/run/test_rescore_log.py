"""``rescore_log``: every rule's numbers on a harness's log equal what the upstream functions give
on the same replies.

The logs in ``tests/fixtures/harness_logs/`` (see its README) are in each harness's exact format,
with hundreds of questions: lmms-eval's ``--log_samples`` JSONL as ``save_results_samples``
writes it at EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3 (ViewSpatial-Bench,
300 questions; MindCube, 240; 3DSRBench's circular subset, 192 copies of 30 questions), and
VLMEvalKit's prediction files as ``infer_data_job`` dumps them at
open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94 (ViewSpatial-Bench as .tsv and
.xlsx, MindCube as .xlsx, 3DSRBench as .tsv) holding the same questions and replies. The expected figures below
were produced by RUNNING the upstream functions at those commits (and at the sets' own:
ZJU-REAL/ViewSpatial-Bench@2e85a5e41a29e7919b1d326d8aba316661579983 ``evaluate.py``
``extract_option`` on the last line; mll-lab-nu/MindCube@6d8fd9acdf5b80769373a21cdbfcf068ab356e0f
``src/evaluation/core/extractors.py`` ``extract_answer``) on the logged replies, outside the
project, never written by hand:

- lmms-eval rules: ``strip_reasoning_tags`` with the default ``--reasoning_tags``, then the task's
  ``process_results`` and its aggregation functions (``viewspatial_aggregate_*``,
  ``mindcube_aggregate_*``, 3DSRBench's ``aggregate_*_accuracy``; 3DSRBench's per category:
  ``aggregate_circular_accuracy`` over the category's records);
- VLMEvalKit's spatial rule: ``compute_mcq_score`` (``can_match_option`` both sides,
  ``exact_match``), the mean of ``hit`` overall and per ``question_type`` / ``category`` as
  ``eval_mcq_score`` groups;
- VLMEvalKit's exact matching (3DSRBench's official reading): ``can_infer(reply, options)``, ``Z``
  when it gives ``False``, scored against the gold and grouped by lmms-eval's aggregations; on the
  prediction file, VLMEvalKit's own ``_3DSRBench.evaluate`` (which gives the same figures).
"""

from __future__ import annotations

import gzip
import shutil
from fractions import Fraction
from pathlib import Path

import pytest

from povagent.run.rescore_log import rescore_log
from povagent_plugins.parsers.mcq.vlmevalkit_load import LOAD_FILTER

FIXTURES = Path(__file__).resolve().parent.parent / "fixtures" / "harness_logs"

VS_CAM_ORI, VS_CAM_REL = "Camera perspective - Object View Orientation", "Camera perspective - Relative Direction"
VS_PER_ORI, VS_PER_REL = "Person perspective - Object View Orientation", "Person perspective - Relative Direction"
VS_SIM = "Person perspective - Scene Simulation Relative Direction"

VIEWSPATIAL = {
    "viewspatial-official": ("31/75", {VS_CAM_ORI: "17/52", VS_CAM_REL: "39/94", VS_PER_ORI: "21/52", VS_PER_REL: "25/51", VS_SIM: "22/51"}),
    "viewspatial": ("133/300", {VS_CAM_ORI: "19/52", VS_CAM_REL: "43/94", VS_PER_ORI: "23/52", VS_PER_REL: "25/51", VS_SIM: "23/51"}),
    "vlmevalkit-spatial": ("9/20", {VS_CAM_ORI: "21/52", VS_CAM_REL: "43/94", VS_PER_ORI: "11/26", VS_PER_REL: "25/51", VS_SIM: "8/17"}),
}
MINDCUBE = {
    "mindcube-official": ("39/80", {"among": "19/40", "around": "33/80", "rotation": "23/40"}),
    "mindcube": ("121/240", {"among": "39/80", "around": "7/16", "rotation": "47/80"}),
    "vlmevalkit-spatial": ("31/60", {"among": "39/80", "around": "19/40", "rotation": "47/80"}),
}
SRBENCH3D_CATEGORIES = {
    "vlmevalkit-exact": {
        "height": "1/6",
        "height_higher": "1/6",
        "location": "1/9",
        "location_above": "1/6",
        "location_closer_to_camera": "0",
        "location_next_to": "1/6",
        "multi_object": "1/10",
        "multi_object_closer_to": "0",
        "multi_object_facing": "0",
        "multi_object_parallel": "1/4",
        "multi_object_same_direction": "0",
        "multi_object_viewpoint_towards_object": "1/4",
        "orientation": "1/16",
        "orientation_in_front_of": "0",
        "orientation_on_the_left": "0",
        "orientation_viewpoint": "1/4",
    },
    "3dsrbench-lmms": {
        "height": "1/6",
        "height_higher": "1/6",
        "location": "2/9",
        "location_above": "1/6",
        "location_closer_to_camera": "1/6",
        "location_next_to": "1/3",
        "multi_object": "1/20",
        "multi_object_closer_to": "0",
        "multi_object_facing": "0",
        "multi_object_parallel": "0",
        "multi_object_same_direction": "0",
        "multi_object_viewpoint_towards_object": "1/4",
        "orientation": "0",
        "orientation_in_front_of": "0",
        "orientation_on_the_left": "0",
        "orientation_viewpoint": "0",
    },
}
SRBENCH3D = {
    "vlmevalkit-exact": {"vanilla_accuracy": "11/24", "flip_accuracy": "19/96", "circular_accuracy": "1/10", "flip_circular_accuracy": "0"},
    "3dsrbench-lmms": {"vanilla_accuracy": "95/192", "flip_accuracy": "11/48", "circular_accuracy": "1/10", "flip_circular_accuracy": "0"},
}


def fixture(name: str, tmp_path: Path) -> Path:
    """The fixture ``name`` in ``tmp_path`` (unpacked where it is kept gzipped)."""
    packed = FIXTURES / f"{name}.gz"
    out = tmp_path / name
    if packed.exists():
        with gzip.open(packed, "rb") as source, out.open("wb") as sink:
            shutil.copyfileobj(source, sink)
    else:
        shutil.copyfile(FIXTURES / name, out)
    return out


def assert_equal_to_upstream(result, expected: dict) -> None:
    got = {r.rule: (r.overall, r.per_category) for r in result.rules}
    assert list(got) == list(expected)
    for rule, (overall, per_category) in expected.items():
        assert got[rule][0] == pytest.approx(float(Fraction(overall)), abs=1e-12), rule
        assert got[rule][1] == pytest.approx({c: float(Fraction(v)) for c, v in per_category.items()}, abs=1e-12), rule


@pytest.mark.parametrize(
    ("name", "harness"),
    [("viewspatial_samples.jsonl", "lmms-eval"), ("ViewSpatialBench_preds.tsv", "vlmevalkit"), ("ViewSpatialBench_preds.xlsx", "vlmevalkit")],
)
def test_viewspatial_logs_score_as_the_upstream_functions_do(name, harness, tmp_path):
    result = rescore_log(fixture(name, tmp_path), harness, "viewspatial", n_boot=0)
    assert (result.items, result.bad_records) == (300, 0)
    assert_equal_to_upstream(result, VIEWSPATIAL)


@pytest.mark.parametrize(("name", "harness"), [("mindcube_samples.jsonl", "lmms-eval"), ("MindCubeBench_preds.xlsx", "vlmevalkit")])
def test_mindcube_logs_score_as_the_upstream_functions_do(name, harness, tmp_path):
    result = rescore_log(fixture(name, tmp_path), harness, "mindcube", n_boot=0)
    assert (result.items, result.bad_records) == (240, 0)
    assert_equal_to_upstream(result, MINDCUBE)


def test_3dsrbench_circular_log_gives_the_four_accuracies_of_the_upstream_aggregations(tmp_path):
    result = rescore_log(fixture("3dsrbench_circular_samples.jsonl", tmp_path), "lmms-eval", "3dsrbench", n_boot=0)
    assert result.items == 192
    for rule in result.rules:
        assert rule.metric == "circular_accuracy"  # the set's headline: the authors' circular evaluation
        assert {m: rule.metrics[m].value for m in SRBENCH3D[rule.rule]} == pytest.approx({m: float(Fraction(v)) for m, v in SRBENCH3D[rule.rule].items()})
    assert_equal_to_upstream(result, {rule: (SRBENCH3D[rule]["circular_accuracy"], cats) for rule, cats in SRBENCH3D_CATEGORIES.items()})


def test_3dsrbench_prediction_file_gives_what_vlmevalkits_own_3dsrbench_evaluate_gives(tmp_path):
    # _3DSRBench.evaluate (vlmeval/dataset/image_mcq.py @ e8e78f05, exact matching): mcq_vanilla_eval's hits,
    # its flip, circular and flip+circular groupings, report_acc per category of the circular groups
    result = rescore_log(fixture("3DSRBench_preds.tsv", tmp_path), "vlmevalkit", "3dsrbench", n_boot=0)
    assert result.items == 192
    official = result.rules[0]
    assert (official.rule, official.metric) == ("vlmevalkit-exact", "circular_accuracy")
    assert {m: official.metrics[m].value for m in SRBENCH3D["vlmevalkit-exact"]} == pytest.approx(
        {m: float(Fraction(v)) for m, v in SRBENCH3D["vlmevalkit-exact"].items()}
    )
    subs = {c: v for c, v in SRBENCH3D_CATEGORIES["vlmevalkit-exact"].items() if "_" in c and c != "multi_object"}
    assert official.per_category == pytest.approx({c: float(Fraction(v)) for c, v in subs.items()})  # the file has no main category


def test_the_official_rule_comes_first_and_each_rule_names_its_commit(tmp_path):
    result = rescore_log(fixture("viewspatial_samples.jsonl", tmp_path), "lmms-eval", "viewspatial", n_boot=0)
    assert [r.official for r in result.rules] == [True, False, False]
    assert [r.source for r in result.rules] == [
        "ZJU-REAL/ViewSpatial-Bench@2e85a5e41a29e7919b1d326d8aba316661579983",
        "EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3",
        "open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94",
    ]


def test_each_rule_says_which_field_of_an_lmms_eval_log_it_read(tmp_path):
    result = rescore_log(fixture("viewspatial_samples.jsonl", tmp_path), "lmms-eval", "viewspatial", n_boot=0)
    reads = {r.rule: r.reads for r in result.rules}
    assert reads["viewspatial-official"] == "resps as written"
    assert reads["vlmevalkit-spatial"] == f"resps, then {LOAD_FILTER}"  # VLMEvalKit reads every reply through pandas
    assert reads["viewspatial"].startswith("resps, then lmms-eval's reasoning-tag strip")
    assert result.stripped == 44  # replies whose logged filtered_resps differs from resps


def test_the_tsv_and_the_xlsx_of_one_run_give_the_same_numbers_and_disagreements(tmp_path):
    tsv = rescore_log(fixture("ViewSpatialBench_preds.tsv", tmp_path), "vlmevalkit", "viewspatial", n_boot=200)
    xlsx = rescore_log(fixture("ViewSpatialBench_preds.xlsx", tmp_path), "vlmevalkit", "viewspatial", n_boot=200)
    assert tsv.rules == xlsx.rules
    assert [d.item for d in tsv.disagreements] == [d.item for d in xlsx.disagreements]


def test_the_disagreements_are_exactly_the_replies_the_rules_read_differently(tmp_path):
    result = rescore_log(fixture("viewspatial_samples.jsonl", tmp_path), "lmms-eval", "viewspatial", n_boot=0)
    assert result.disagreements_total == len(result.disagreements) == 41
    assert all(len(set(d.labels.values())) > 1 for d in result.disagreements)
    # every question whose hit differs between two rules is among them
    hits = {r.rule: round(r.overall * result.items) for r in result.rules}
    assert len(set(hits.values())) > 1
    first = result.disagreements[0]
    assert set(first.labels) == set(first.correct) == set(hits)


def test_every_figure_has_a_confidence_interval_around_it(tmp_path):
    result = rescore_log(fixture("mindcube_samples.jsonl", tmp_path), "lmms-eval", "mindcube", n_boot=500)
    for rule in result.rules:
        assert rule.overall_ci is not None and rule.overall_ci[0] <= rule.overall <= rule.overall_ci[1]
        for category, value in rule.per_category.items():
            lo, hi = rule.per_category_ci[category]
            assert lo <= value <= hi


def test_a_bad_record_is_named_in_one_line_and_the_rest_are_still_scored(tmp_path):
    log = fixture("viewspatial_samples.jsonl", tmp_path)
    lines = log.read_text(encoding="utf-8").splitlines()
    lines.insert(3, '{"doc_id": 9999, "target": "A. left", "filtered_resps": 12}')
    lines.insert(7, "{not json")
    log.write_text("\n".join(lines) + "\n", encoding="utf-8")
    result = rescore_log(log, "lmms-eval", "viewspatial", n_boot=0)
    assert (result.items, result.bad_records) == (300, 2)
    assert result.problems == [
        f"{log}: line 4.filtered_resps: required, the reply as text of at most 1000000 characters; record left out",
        f"{log}: line 8: not a JSON record (Expecting property name enclosed in double quotes); record left out",
    ]
    assert_equal_to_upstream(result, VIEWSPATIAL)


def test_an_unknown_set_is_refused_naming_the_known_ones_before_the_file_is_read(tmp_path):
    from povagent.errors import PluginError

    with pytest.raises(
        PluginError, match=r"unknown set .vsi.: a log can be scored as 3dsrbench, mindcube, mmsi, mmsi-circular, omnispatial, viewspatial, vsibench"
    ):
        rescore_log(tmp_path / "not-there.jsonl", "lmms-eval", "vsi")


# MMSI-Bench and OmniSpatial. Figures produced by running, on the logged replies: the set's own code
# (InternRobotics/MMSI-Bench@5de2f3d2eb0159dbcc76790074029aa400143603 vlmeval/dataset/mmsi_bench.py
# MMSIBenchDataset.evaluate; qizekun/OmniSpatial@208bac258d8671c6857b3be2834997936ba7fc51 api_eval.py
# process_info, --eval_type re, the model call replaced by the logged reply, its per-task and per-sub-task
# means without the printout's 1e-6 in the denominator), lmms-eval@75571cfe's strip_reasoning_tags then
# mmsi_bench's msr_process_results and msr_aggregate_results (per l2_category), omni_spatial's
# omni_spatial_process_results and its aggregations (per task_type; its per-item scores grouped by
# sub_task_type), omnispatial_test's omnispatial_process_results and omnispatial_aggregate_results (its
# sub_task_accuracies and task_accuracies), and VLMEvalKit@e8e78f05's compute_mcq_score grouped as
# MMSIBench.evaluate (category) and OmniSpatialBench.evaluate (task_type, sub_task_type) group it. The
# corrected re reading is api_eval.py's pattern with its fallback left out: a reply with no line is no hit.

MMSI_CATEGORIES = {  # VLMEvalKit's MMSIBench_wo_circular category -> lmms-eval's l2_category (its CATEGORY_ALIASES)
    "Pos-Cam-Cam": "Positional Relationship (Cam.–Cam.)",
    "Pos-Obj-Obj": "Positional Relationship (Obj.–Obj.)",
    "Pos-Reg-Reg": "Positional Relationship (Reg.–Reg.)",
    "Pos-Cam-Obj": "Positional Relationship (Cam.–Obj.)",
    "Pos-Obj-Reg": "Positional Relationship (Obj.–Reg.)",
    "Pos-Cam-Reg": "Positional Relationship (Cam.–Reg.)",
    "Attr-Meas": "Attribute (Meas.)",
    "Attr-Appr": "Attribute (Appr.)",
    "Motion-Cam": "Motion (Cam.)",
    "Motion-Obj": "Motion (Obj.)",
    "MSR": "MSR",
}
_MMSI_ORDER = list(MMSI_CATEGORIES)
MMSI = {
    "mmsi-official": ("29/80", ["4/21", "10/21", "7/23", "15/22", "1/12", "7/22", "10/21", "7/22", "1/3", "8/21", "5/11"]),
    "mmsi-lmms": ("23/60", ["1/7", "10/21", "7/23", "15/22", "5/24", "9/22", "10/21", "7/22", "8/21", "3/7", "9/22"]),
    "vlmevalkit-spatial": ("17/48", ["4/21", "10/21", "7/23", "15/22", "1/24", "7/22", "8/21", "7/22", "1/3", "10/21", "9/22"]),
}
OMNI_SUBS = [
    "Manipulation",
    "Motion_Analysis",
    "Traffic_Analysis",
    "Localization",
    "Geospatial_Strategy",
    "Pattern_Recognition",
    "Geometric_Reasoning",
    "Egocentric",
    "Allocentric",
    "Hypothetical",
]
OMNI_TASKS = ["Dynamic_Reasoning", "Spatial_Interaction", "Complex_Logic", "Perspective_Taking"]
OMNISPATIAL = {  # (overall, the ten sub-tasks in OMNI_SUBS' order, the four task types in OMNI_TASKS')
    "omnispatial-re": ("19/55", ["11/21", "8/23", "3/10", "8/21", "7/23", "9/23", "3/11", "7/23", "8/21", "6/23"], ["19/44", "21/64", "1/3", "21/67"]),
    "omnispatial-lmms-direct": ("31/110", ["5/21", "10/23", "1/5", "5/21", "6/23", "6/23", "9/22", "2/23", "1/3", "8/23"], ["15/44", "15/64", "1/3", "17/67"]),
    "omnispatial-lmms-re": ("81/220", ["11/21", "10/23", "2/5", "3/7", "7/23", "9/23", "3/11", "6/23", "8/21", "7/23"], ["21/44", "3/8", "1/3", "21/67"]),
    "omnispatial-re-corrected": ("21/110", ["5/21", "4/23", "3/20", "5/21", "4/23", "6/23", "3/22", "5/23", "4/21", "3/23"], ["9/44", "3/16", "1/5", "12/67"]),
    "vlmevalkit-spatial": ("23/55", ["3/7", "11/23", "1/5", "10/21", "7/23", "12/23", "9/22", "9/23", "10/21", "11/23"], ["5/11", "21/64", "7/15", "30/67"]),
}


@pytest.mark.parametrize(("name", "harness"), [("mmsi_bench_samples.jsonl", "lmms-eval"), ("MMSIBench_wo_circular_preds.tsv", "vlmevalkit")])
def test_mmsi_logs_score_as_the_upstream_functions_do(name, harness, tmp_path):
    result = rescore_log(fixture(name, tmp_path), harness, "mmsi", n_boot=0)
    assert (result.items, result.bad_records) == (240, 0)
    names = [MMSI_CATEGORIES[c] for c in _MMSI_ORDER] if harness == "lmms-eval" else _MMSI_ORDER  # each log as its harness names them
    assert_equal_to_upstream(result, {rule: (overall, dict(zip(names, cells))) for rule, (overall, cells) in MMSI.items()})


@pytest.mark.parametrize(
    ("name", "harness", "sub_task"),
    [
        ("omni_spatial_samples.jsonl", "lmms-eval", str),  # lmms-eval's omni_spatial task: sub_task_type as the set writes it
        ("omnispatial_test_samples.jsonl", "lmms-eval", lambda s: f"omnispatial_{s.lower()}"),  # omnispatial_test's own sub_task
        ("OmniSpatialBench_manual_cot_preds.tsv", "vlmevalkit", str),
    ],
)
def test_omnispatial_logs_score_as_the_upstream_functions_do(name, harness, sub_task, tmp_path):
    result = rescore_log(fixture(name, tmp_path), harness, "omnispatial", n_boot=0)
    assert (result.items, result.bad_records) == (220, 0)
    expected = {
        rule: (overall, {**{sub_task(s): v for s, v in zip(OMNI_SUBS, subs)}, **dict(zip(OMNI_TASKS, tasks))})
        for rule, (overall, subs, tasks) in OMNISPATIAL.items()
    }
    assert_equal_to_upstream(result, expected)


def test_omnispatial_names_its_read_a_fallback_and_lmms_evals_strip_per_rule(tmp_path):
    result = rescore_log(fixture("omnispatial_test_samples.jsonl", tmp_path), "lmms-eval", "omnispatial", n_boot=0)
    rules = {r.rule: r for r in result.rules}
    assert [r.official for r in result.rules] == [True, False, False, False, False]
    assert rules["omnispatial-re"].source == "qizekun/OmniSpatial@208bac258d8671c6857b3be2834997936ba7fc51"
    assert (
        rules["omnispatial-lmms-re"].source == rules["omnispatial-lmms-direct"].source == "EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3"
    )
    assert rules["omnispatial-re"].reads == "resps as written"
    assert rules["omnispatial-lmms-re"].reads.startswith("resps, then lmms-eval's reasoning-tag strip")
    # the fallback answers every reply; its corrected reading only the replies with an "Answer: X" line
    assert rules["omnispatial-re"].answered == 220 > rules["omnispatial-re-corrected"].answered
    assert result.stripped == 59


def test_mmsi_options_are_read_from_the_question_as_the_set_writes_them(tmp_path):
    from povagent.results.harness_log_files import read_harness_log

    for name, harness in (("mmsi_bench_samples.jsonl", "lmms-eval"), ("MMSIBench_wo_circular_preds.tsv", "vlmevalkit")):
        first = read_harness_log(fixture(name, tmp_path), harness).replies[0]
        assert first.options == (("A", "A blue vase"), ("B", "Left"), ("C", "East"), ("D", "2.0 m")), name


# VSI-Bench, multiple-choice and numerical questions: 230 questions of its ten types in lmms-eval's vsibench
# log. Figures from RUNNING vision-x-nyu/thinking-in-space@51e089c3ae69b9435e9489058610f5b3964c56a8
# lmms_eval/tasks/vsibench/utils.py vsibench_process_results on the replies as written and
# vsibench_aggregate_results (it prints percent; here / 100), and lmms-eval@75571cfe's strip_reasoning_tags,
# vsibench_process_results and _compute_all_subscores (vsibench_aggregate_overall rounds the overall to 6
# places: 0.334122). Neither reports the three direction levels apart: their mean is object_rel_direction.
# VLMEvalKit's figures: open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94 VsiBench.evaluate (no judge:
# compute_mcq_score, compute_na_score, _aggregate) RUN on the same replies (resps where kept, else filtered_resps)
# dumped as its prediction file (.tsv).
VSIBENCH_TYPES = [
    "obj_appearance_order",
    "object_abs_distance",
    "object_counting",
    "object_rel_distance",
    "object_size_estimation",
    "room_size_estimation",
    "route_planning",
    "object_rel_direction",
]
VSIBENCH = {
    "vsibench": (
        17.35806258958433,
        [23.076923076923077, 21.200000000000003, 7.6, 4.3478260869565215, 19.090909090909093, 23.04347826086957, 21.73913043478261, 18.766233766233764],
    ),
    "vlmevalkit-vsibench": (
        43.697944567509786,
        [42.30769230769231, 50.4, 49.599999999999994, 17.391304347826086, 42.272727272727266, 52.17391304347826, 47.82608695652174, 47.61183261183262],
    ),
    "vsibench-lmms": (
        33.41217357521705,
        [23.076923076923078, 50.4, 49.599999999999994, 4.3478260869565216, 42.27272727272727, 52.17391304347826, 21.739130434782608, 23.686868686868687],
    ),
}


def test_vsibench_log_gives_the_sets_overall_and_each_harnesss_as_the_upstream_functions_do(tmp_path):
    result = rescore_log(fixture("vsibench_samples.jsonl", tmp_path), "lmms-eval", "vsibench", n_boot=0)
    assert (result.items, result.numerical, result.bad_records) == (230, 95, 0)
    assert [(r.rule, r.official, r.metric) for r in result.rules] == [
        ("vsibench", True, "score"),
        ("vlmevalkit-vsibench", False, "score"),
        ("vsibench-lmms", False, "score"),
    ]
    for rule in result.rules:
        overall, per_type = VSIBENCH[rule.rule]
        cells = dict(rule.per_category)
        cells["object_rel_direction"] = sum(cells.pop(f"object_rel_direction_{level}") for level in ("easy", "medium", "hard")) / 3
        assert rule.overall == pytest.approx(overall / 100, rel=1e-12)
        assert cells == pytest.approx({t: v / 100 for t, v in zip(VSIBENCH_TYPES, per_type)}, rel=1e-12)
    assert round(result.rules[2].overall, 6) == 0.334122  # vsibench_aggregate_overall's own figure


def test_a_numerical_reply_is_read_as_a_number_and_shown_as_one(tmp_path):
    result = rescore_log(fixture("vsibench_samples.jsonl", tmp_path), "lmms-eval", "vsibench", n_boot=0)
    reading = {r.rule: r.answered for r in result.rules}
    # lmms-eval's extract_number finds "About 3 meters"; the first word does not; VLMEvalKit reads a capital A-F standing
    # alone ("Option B") and the last number, and none of them an option's text ("sofa")
    assert reading == {"vsibench": 156, "vlmevalkit-vsibench": 192, "vsibench-lmms": 205}
    about = [d for d in result.disagreements if d.reply.startswith("About ")]
    assert len(about) == 8
    for d in about:  # "About 8.5 meters.": the set's first word is no number; lmms-eval's extract_number and VLMEvalKit read 8.5
        assert d.labels["vsibench"] is None and d.labels["vsibench-lmms"] == d.labels["vlmevalkit-vsibench"] == d.reply.split()[1]
    # a numerical hit meets every threshold: within 5% of the gold (the 0.95 threshold)
    full = [d for d in result.disagreements if d.gold[0].isdigit() and d.correct["vsibench-lmms"]]
    assert full and all(abs(float(d.labels["vsibench-lmms"]) - float(d.gold)) <= 0.05 * float(d.gold) + 1e-9 for d in full)


# VSI-Bench as VLMEvalKit's prediction file: 320 questions of the ten types (candidates a list literal, answer the
# ground_truth), replies drawn from 61 forms (the lmms-eval fixture's, and "1,200 mm", "between 2 and 3 meters", "[2.5]",
# "<answer>3</answer>", "3-4 m", "N/A", "twenty-one", "1.20e+02", zero-width spaces, "<answer>B</answer>", "B or C"...). Figures
# from RUNNING VLMEvalKit@e8e78f05 VsiBench.evaluate on the .tsv and on the .xlsx (equal), and the set's own and lmms-eval's
# functions (as above) on the replies; per question type, the three direction levels apart (upstream's per-type means).
VSIBENCH_VLMEVALKIT_FILE = {
    "vsibench": (
        14.42240829616304,
        {
            "object_rel_direction_easy": 0.058823529411764705,
            "object_rel_direction_medium": 0.06451612903225806,
            "object_rel_direction_hard": 0.22580645161290322,
            "object_rel_distance": 0.25806451612903225,
            "route_planning": 0.15625,
            "obj_appearance_order": 0.13333333333333333,
            "object_abs_distance": 0.19090909090909092,
            "object_counting": 0.08857142857142858,
            "object_size_estimation": 0.08125,
            "room_size_estimation": 0.12903225806451613,
        },
    ),
    "vlmevalkit-vsibench": (
        47.910093518712465,
        {
            "obj_appearance_order": 0.36666666666666664,
            "object_rel_direction_easy": 0.5,
            "object_rel_direction_hard": 0.5483870967741935,
            "object_rel_direction_medium": 0.2903225806451613,
            "object_rel_distance": 0.5806451612903226,
            "route_planning": 0.59375,
            "object_abs_distance": 0.39393939393939387,
            "object_counting": 0.4714285714285714,
            "object_size_estimation": 0.415625,
            "room_size_estimation": 0.5645161290322581,
        },
    ),
    "vsibench-lmms": (
        34.736171457219256,
        {
            "object_rel_direction_easy": 0.11764705882352941,
            "object_rel_direction_medium": 0.12903225806451613,
            "object_rel_direction_hard": 0.22580645161290322,
            "object_rel_distance": 0.2903225806451613,
            "route_planning": 0.21875,
            "obj_appearance_order": 0.23333333333333334,
            "object_abs_distance": 0.5303030303030303,
            "object_counting": 0.5,
            "object_size_estimation": 0.39062499999999994,
            "room_size_estimation": 0.45806451612903226,
        },
    ),
}
#: VsiBench._aggregate's own table for the same file (times 100): the direction levels merged.
VLMEVALKIT_TABLE = {
    "object_counting": 47.14285714285714,
    "object_abs_distance": 39.393939393939384,
    "object_size_estimation": 41.5625,
    "room_size_estimation": 56.451612903225815,
    "object_rel_distance": 58.06451612903226,
    "object_rel_direction": 44.623655913978496,
    "route_planning": 59.375,
    "obj_appearance_order": 36.666666666666664,
}


@pytest.mark.parametrize("name", ["VSI-Bench_preds.tsv", "VSI-Bench_preds.xlsx"])
def test_vsibench_prediction_file_gives_what_vlmevalkits_own_evaluate_and_the_other_rules_give(name, tmp_path):
    result = rescore_log(fixture(name, tmp_path), "vlmevalkit", "vsibench", n_boot=0)
    assert (result.items, result.numerical, result.bad_records) == (320, 131, 0)
    assert [(r.rule, r.official, r.harness) for r in result.rules] == [
        ("vsibench", True, "VSI-Bench"),
        ("vlmevalkit-vsibench", False, "VLMEvalKit"),
        ("vsibench-lmms", False, "lmms-eval"),
    ]
    for rule in result.rules:
        overall, per_type = VSIBENCH_VLMEVALKIT_FILE[rule.rule]
        assert rule.overall == pytest.approx(overall / 100, rel=1e-12), rule.rule
        assert rule.per_category == pytest.approx(per_type, rel=1e-12), rule.rule
    table = dict(result.rules[1].per_category)
    table["object_rel_direction"] = sum(table.pop(f"object_rel_direction_{level}") for level in ("easy", "medium", "hard")) / 3
    assert {t: 100 * v for t, v in table.items()} == pytest.approx(VLMEVALKIT_TABLE, rel=1e-12)
    assert {r.rule: r.answered for r in result.rules} == {"vsibench": 215, "vlmevalkit-vsibench": 270, "vsibench-lmms": 295}


def test_vlmevalkit_keeps_the_direction_levels_apart_when_one_has_no_question(tmp_path):
    # the same file without its object_rel_direction_hard rows: VsiBench._aggregate merges the levels only when all three
    # are there, so easy and medium count as two types (46.4099278111375, RUN); the set's code would raise, povagent's
    # official reading averages the two levels present
    import csv

    full = fixture("VSI-Bench_preds.tsv", tmp_path)
    with full.open(encoding="utf-8", newline="") as source:
        rows = [row for row in csv.reader(source, dialect="excel-tab") if row[5] != "object_rel_direction_hard"]
    kept = tmp_path / "VSI-Bench_no_hard.tsv"
    with kept.open("w", encoding="utf-8", newline="") as sink:
        csv.writer(sink, dialect="excel-tab", quoting=csv.QUOTE_ALL).writerows(rows)
    result = rescore_log(kept, "vlmevalkit", "vsibench", n_boot=0)
    assert result.items == 289
    rules = {r.rule: r for r in result.rules}
    assert rules["vlmevalkit-vsibench"].overall == pytest.approx(0.464099278111375, rel=1e-12)
    cells = rules["vsibench"].per_category
    merged = (cells["object_rel_direction_easy"] + cells["object_rel_direction_medium"]) / 2
    others = [v for k, v in cells.items() if not k.startswith("object_rel_direction")]
    assert rules["vsibench"].overall == pytest.approx((sum(others) + merged) / (len(others) + 1), rel=1e-12)


def test_a_number_logged_as_the_gold_of_a_choice_set_is_named_and_left_out(tmp_path):
    log = tmp_path / "viewspatial.jsonl"
    log.write_text(
        '{"doc_id": 1, "target": "B. left", "filtered_resps": "B", "input": "Choices: A. right\\nB. left"}\n'
        '{"doc_id": 2, "target": "3.5", "filtered_resps": "3.5"}\n',
        encoding="utf-8",
    )
    result = rescore_log(log, "lmms-eval", "viewspatial", n_boot=0)
    assert (result.items, result.bad_records) == (1, 1)
    assert result.problems == [f"{log}: line 2.target: the target '3.5' is a number, and viewspatial's answers are option labels; record left out"]


def test_a_number_as_the_answer_of_a_choice_sets_prediction_file_is_named_by_its_column_and_left_out(tmp_path):
    log = tmp_path / "Model_ViewSpatialBench.tsv"
    log.write_text('"index"\t"candidates"\t"answer"\t"prediction"\n"1"\t"[\'A. right\', \'B. left\']"\t"B"\t"B"\n"2"\t""\t"3.5"\t"3.5"\n', encoding="utf-8")
    result = rescore_log(log, "vlmevalkit", "viewspatial", n_boot=0)
    assert (result.items, result.bad_records) == (1, 1)
    assert result.problems == [f"{log}: row 3.answer: the answer '3.5' is a number, and viewspatial's answers are option labels; record left out"]


# MMSI-Bench's circular split (60 questions, 240 copies; ``MMSI_Bench_Circular_preds.tsv`` as the
# authors' VLMEvalKit fork writes it, ``MMSIBench_circular_preds.tsv`` as VLMEvalKit does, the same
# copies and replies): the official figures are the authors' MMSIBenchCircular.evaluate
# (InternRobotics/MMSI-Bench@5de2f3d2), VLMEvalKit's are mcq_circular_eval with exact matching and
# report_acc (VLMEvalKit@e8e78f05), each run on the file's replies.
_PR = "Positional Relationship"
MMSI_CIRCULAR_CATEGORIES = [
    f"{_PR} (Cam.–Cam.)",
    f"{_PR} (Obj.–Obj.)",
    f"{_PR} (Reg.–Reg.)",
    f"{_PR} (Cam.–Obj.)",
    f"{_PR} (Obj.–Reg.)",
    f"{_PR} (Cam.–Reg.)",
    "Attribute (Meas.)",
    "Attribute (Appr.)",
    "Motion (Cam.)",
    "Motion (Obj.)",
    "MSR",
]
MMSI_CIRCULAR = {
    "mmsi-official": ("13/60", ["1/6", "1/6", "0", "1/6", "1/2", "1/5", "1/5", "0", "2/5", "0", "3/5"]),
    "vlmevalkit-exact": ("3/20", ["0", "1/3", "0", "1/6", "0", "2/5", "0", "1/5", "2/5", "0", "1/5"]),
}
#: the authors' Vanilla column: each question's first copy
MMSI_CIRCULAR_VANILLA = "31/60"


@pytest.mark.parametrize("name", ["MMSI_Bench_Circular_preds.tsv", "MMSIBench_circular_preds.tsv"])
def test_mmsi_circular_prediction_files_score_as_the_upstream_circular_evaluations_do(name, tmp_path):
    result = rescore_log(fixture(name, tmp_path), "vlmevalkit", "mmsi-circular", n_boot=0)
    assert (result.items, result.bad_records) == (240, 0)
    expected = {rule: (overall, dict(zip(MMSI_CIRCULAR_CATEGORIES, cells))) for rule, (overall, cells) in MMSI_CIRCULAR.items()}
    assert_equal_to_upstream(result, expected)
    official = result.rules[0]
    assert official.metric == "circular_accuracy" and official.metrics["circular_accuracy"].n == 60
    assert official.metrics["vanilla_accuracy"].value == pytest.approx(float(Fraction(MMSI_CIRCULAR_VANILLA)), abs=1e-12)
