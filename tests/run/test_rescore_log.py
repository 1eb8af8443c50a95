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
    "vlmevalkit-exact": {"height": "1/6", "height_higher": "1/6", "location": "1/9", "location_above": "1/6", "location_closer_to_camera": "0",
                         "location_next_to": "1/6", "multi_object": "1/10", "multi_object_closer_to": "0", "multi_object_facing": "0",
                         "multi_object_parallel": "1/4", "multi_object_same_direction": "0", "multi_object_viewpoint_towards_object": "1/4",
                         "orientation": "1/16", "orientation_in_front_of": "0", "orientation_on_the_left": "0", "orientation_viewpoint": "1/4"},
    "3dsrbench-lmms": {"height": "1/6", "height_higher": "1/6", "location": "2/9", "location_above": "1/6", "location_closer_to_camera": "1/6",
                       "location_next_to": "1/3", "multi_object": "1/20", "multi_object_closer_to": "0", "multi_object_facing": "0",
                       "multi_object_parallel": "0", "multi_object_same_direction": "0", "multi_object_viewpoint_towards_object": "1/4",
                       "orientation": "0", "orientation_in_front_of": "0", "orientation_on_the_left": "0", "orientation_viewpoint": "0"},
}  # fmt: skip
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
    ("name", "harness"), [("viewspatial_samples.jsonl", "lmms-eval"), ("ViewSpatialBench_preds.tsv", "vlmevalkit"), ("ViewSpatialBench_preds.xlsx", "vlmevalkit")]
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
    assert reads["vlmevalkit-spatial"] == "resps as written"
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

    with pytest.raises(PluginError, match=r"unknown set 'vsi': a log can be scored as 3dsrbench, mindcube, mmsi, omnispatial, viewspatial"):
        rescore_log(tmp_path / "not-there.jsonl", "lmms-eval", "vsi")
