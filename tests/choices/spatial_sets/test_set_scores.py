"""MMSI-Bench and OmniSpatial scored end to end: oracle replies score 100% under every rule, and
canned replies give, per rule, the overall and per-category accuracies computed by hand below.

How each rule reads each canned reply is pinned against the upstream functions in
``tests/choices/mmsi_corpus.yaml`` and ``omnispatial_corpus.yaml`` (and, for VLMEvalKit's
``can_match_option``, was checked by running it at e8e78f05); the aggregates are the sets' own
(plain means overall, per task type and per sub-task), counted here by hand from the hits
written beside each reply.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline

from ..queued_runs import run_with_queued_replies
from .conftest import MMSI_ROWS, OFFLINE_PLUGIN, OMNI_RECORDS

PR_CAM_OBJ, PR_OBJ_OBJ, MEAS, MOTION_CAM, MSR = (
    "Positional Relationship (Cam.-Obj.)",
    "Positional Relationship (Obj.-Obj.)",
    "Attribute (Meas.)",
    "Motion (Cam.)",
    "MSR",
)

#: one reply per MMSI row (gold in brackets), and whether each rule hits: official, lmms-eval, VLMEvalKit
MMSI_REPLIES = [
    ("``A``", 1, 1, 1),                    # [A]
    ("the answer is b", 0, 1, 1),          # [B] lower case: lmms-eval and VLMEvalKit only
    ("A bike is near, so C", 1, 1, 0),     # [C] the article skipped; VLMEvalKit reads nothing
    ("<think>D</think>A", 1, 0, 1),        # [D] lmms-eval strips the block first
    ("I cannot tell.", 0, 0, 0),           # [A]
    ("B", 1, 1, 1),                        # [B]
    ("`B`", 1, 1, 1),                      # [B]
    ("Answer: c", 0, 1, 1),                # [C]
    ("A\nB", 0, 0, 0),                     # [A] "A" then a letter: skipped; B read
    ("D", 1, 1, 1),                        # [D]
    ("The answer is ``D``.", 1, 1, 1),     # [D]
]  # fmt: skip
MMSI_EXPECTED = {
    "mmsi-official": {"overall": 7 / 11, PR_CAM_OBJ: 2 / 3, PR_OBJ_OBJ: 1 / 2, MEAS: 1.0, MOTION_CAM: 0.0, MSR: 1.0},
    "mmsi-lmms": {"overall": 8 / 11, PR_CAM_OBJ: 1.0, PR_OBJ_OBJ: 0.0, MEAS: 1.0, MOTION_CAM: 0.5, MSR: 1.0},
    "vlmevalkit-spatial": {"overall": 8 / 11, PR_CAM_OBJ: 2 / 3, PR_OBJ_OBJ: 1 / 2, MEAS: 1.0, MOTION_CAM: 0.5, MSR: 1.0},
}

#: one reply per OmniSpatial record (gold in brackets), and whether each rule hits:
#: re, re-corrected, json, direct, lmms-direct (omni_spatial), lmms-re (omnispatial_test)
OMNI_REPLIES = [
    ("I cannot tell.", 1, 0, 1, 0, 0, 1),                          # [A] Ego: no Answer line reads A
    ("Answer: B", 1, 1, 0, 0, 0, 1),                               # [B] Ego
    ("answer: c", 0, 0, 0, 0, 0, 0),                               # [C] Ego: read 'c', never 'C'
    ("B", 0, 0, 0, 1, 1, 0),                                       # [B] Allo
    ("No idea", 1, 0, 1, 0, 0, 1),                                 # [A] Allo (two options)
    ('```json\n{"answer": "D"}\n```', 0, 0, 1, 0, 0, 0),           # [D] Hypo
    ("<think>Answer: B</think>\nAnswer: A", 1, 1, 1, 0, 1, 1),     # [A] Hypo
    ("Answer: B", 0, 0, 1, 1, 1, 0),                               # [A] Motion_Analysis
    ("<think>Answer: B</think>", 1, 1, 0, 0, 0, 0),                # [B] Manipulation: lmms-eval strips it all
    ("Answer: C", 1, 1, 0, 0, 0, 1),                               # [C] Geometric_Reasoning
    ('{"answer": "d"}', 0, 0, 1, 0, 0, 0),                         # [D] Traffic_Analysis
    ("b) right", 0, 0, 0, 1, 1, 0),                                # [B] Localization
]  # fmt: skip
OMNI_RULES = ("omnispatial-re", "omnispatial-re-corrected", "omnispatial-json", "omnispatial-direct", "omnispatial-lmms-direct", "omnispatial-lmms-re")
EGO, ALLO, HYPO, PT = "Egocentric", "Allocentric", "Hypothetical", "Perspective_Taking"
OMNI_EXPECTED = {  # overall; Perspective_Taking and its three sub-tasks; the other task types
    "omnispatial-re": {"overall": 6 / 12, PT: 4 / 7, EGO: 2 / 3, ALLO: 1 / 2, HYPO: 1 / 2, "Dynamic_Reasoning": 1 / 2,
                       "Complex_Logic": 1.0, "Spatial_Interaction": 0.0},
    "omnispatial-re-corrected": {"overall": 4 / 12, PT: 2 / 7, EGO: 1 / 3, ALLO: 0.0, HYPO: 1 / 2, "Dynamic_Reasoning": 1 / 2,
                                 "Complex_Logic": 1.0, "Spatial_Interaction": 0.0},
    "omnispatial-json": {"overall": 6 / 12, PT: 4 / 7, EGO: 1 / 3, ALLO: 1 / 2, HYPO: 1.0, "Dynamic_Reasoning": 1 / 2,
                         "Complex_Logic": 0.0, "Spatial_Interaction": 1 / 2},
    "omnispatial-direct": {"overall": 3 / 12, PT: 1 / 7, EGO: 0.0, ALLO: 1 / 2, HYPO: 0.0, "Dynamic_Reasoning": 1 / 2,
                           "Complex_Logic": 0.0, "Spatial_Interaction": 1 / 2},
    "omnispatial-lmms-direct": {"overall": 4 / 12, PT: 2 / 7, EGO: 0.0, ALLO: 1 / 2, HYPO: 1 / 2, "Dynamic_Reasoning": 1 / 2,
                                "Complex_Logic": 0.0, "Spatial_Interaction": 1 / 2},
    "omnispatial-lmms-re": {"overall": 5 / 12, PT: 4 / 7, EGO: 2 / 3, ALLO: 1 / 2, HYPO: 1 / 2, "Dynamic_Reasoning": 0.0,
                            "Complex_Logic": 1.0, "Spatial_Interaction": 0.0},
}  # fmt: skip


def _run(tmp_path, plugin, queued_backend, path, format, replies, *, parser=None, scorer="choice", name="run"):
    config = {"plugins": [str(plugin)], "dataset": {"path": str(path), "format": format}, "backend": "queued",
              "strategy": "choice", "scorers": [scorer], "runs": 1, "concurrency": 1, "timeout": 5, "output": str(tmp_path / name)}  # fmt: skip
    if parser is not None:
        config["parser"] = parser
    (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(config))
    queued_backend.queue(*replies)
    return run_pipeline(load_pipeline(tmp_path / f"{name}.yaml"))


def _values(summary, scorer="choice", metric="accuracy") -> dict[str, float]:
    metrics = summary.metrics[scorer]
    return {"overall": metrics.overall[metric].value, **{k: v[metric].value for k, v in (metrics.per_category or {}).items()}}


@pytest.fixture
def mmsi_copy(tmp_path, mmsi_parquet, offline_plugin_file):
    shutil.copy(mmsi_parquet, tmp_path / "MMSI_Bench.parquet")
    return tmp_path / "MMSI_Bench.parquet"


@pytest.fixture
def omni_copy(tmp_path, omnispatial_folder, offline_plugin_file):
    shutil.copytree(omnispatial_folder, tmp_path / "OmniSpatial-test")
    return tmp_path / "OmniSpatial-test" / "data.json"


def _module_run(folder, format, replies):
    """A run of the ``queued`` backend made once a module in ``folder`` (its tests read it, or
    write beside it: rescored folders, reports elsewhere)."""
    config = {"plugins": [str(Path(shutil.copy(OFFLINE_PLUGIN, folder / "offline_plugin.py")).resolve())],
              "dataset": {"path": str(folder / ("MMSI_Bench.parquet" if format == "mmsi" else "OmniSpatial-test/data.json")), "format": format},
              "backend": "queued", "strategy": "choice", "scorers": ["choice"], "runs": 1, "concurrency": 1, "timeout": 5,
              "output": str(folder / "run")}  # fmt: skip
    (folder / "run.yaml").write_text(yaml.safe_dump(config))
    return run_with_queued_replies(folder / "run.yaml", replies)


@pytest.fixture(scope="module")
def mmsi_run_made(tmp_path_factory, mmsi_parquet):
    folder = tmp_path_factory.mktemp("mmsi-run")
    shutil.copy(mmsi_parquet, folder / "MMSI_Bench.parquet")
    return _module_run(folder, "mmsi", [r for r, *_ in MMSI_REPLIES])


@pytest.fixture(scope="module")
def omni_run_made(tmp_path_factory, omnispatial_folder):
    folder = tmp_path_factory.mktemp("omni-run")
    shutil.copytree(omnispatial_folder, folder / "OmniSpatial-test")
    return _module_run(folder, "omnispatial", [r for r, *_ in OMNI_REPLIES])


@pytest.fixture
def mmsi_run(mmsi_run_made, queued_backend):
    """The module's MMSI run, read while a ``queued`` backend is registered (as when it ran)."""
    return mmsi_run_made


@pytest.fixture
def omni_run(omni_run_made, queued_backend):
    """The module's OmniSpatial run, read while a ``queued`` backend is registered (as when it ran)."""
    return omni_run_made


def test_the_oracle_backend_scores_every_mmsi_question_under_the_set_s_rule(tmp_path, mmsi_copy, offline_plugin_file):
    config = {"plugins": [str(offline_plugin_file)], "dataset": {"path": str(mmsi_copy), "format": "mmsi"}, "backend": "oracle",
              "strategy": "choice", "runs": 1, "concurrency": 2, "timeout": 5, "output": str(tmp_path / "oracle")}  # fmt: skip
    (tmp_path / "oracle.yaml").write_text(yaml.safe_dump(config))
    result = run_pipeline(load_pipeline(tmp_path / "oracle.yaml"))
    assert result.n_total == len(MMSI_ROWS) and _values(result.summary)["overall"] == 1.0


@pytest.mark.parametrize(("parser", "form"), [("mmsi-official", "``{}``"), ("mmsi-lmms", "``{}``"), ("mmsi-official", "{}")])
def test_oracle_replies_score_every_mmsi_question(tmp_path, mmsi_copy, offline_plugin_file, queued_backend, parser, form):
    replies = [form.format(gold) for *_, gold in MMSI_ROWS]
    result = _run(tmp_path, offline_plugin_file, queued_backend, mmsi_copy, "mmsi", replies, parser=parser)
    assert set(_values(result.summary).values()) == {1.0}


ORACLE_FORMS = {  # each OmniSpatial rule with the reply its prompt asks for
    "omnispatial-re": "Reasoning.\nAnswer: {}", "omnispatial-re-corrected": "Answer: {}", "omnispatial-json": '```json\n{{"answer": "{}"}}\n```',
    "omnispatial-direct": "{}", "omnispatial-lmms-direct": "<think>hmm</think>{}", "omnispatial-lmms-re": "Answer: {}",
}  # fmt: skip


@pytest.mark.parametrize("parser", OMNI_RULES)
def test_oracle_replies_score_every_omnispatial_question(tmp_path, omni_copy, offline_plugin_file, queued_backend, parser):
    replies = [ORACLE_FORMS[parser].format("ABCD"[gold]) for *_, gold in OMNI_RECORDS]
    result = _run(tmp_path, offline_plugin_file, queued_backend, omni_copy, "omnispatial", replies, parser=parser)
    assert set(_values(result.summary).values()) == {1.0}


def test_mmsi_is_read_by_its_own_rule_unless_told_otherwise(mmsi_run):
    assert yaml.safe_load((mmsi_run.run_dir / "config.yaml").read_text())["parser"]["name"] == "mmsi-official"
    hits = [row.scores.get("choice", {}).get("correct", False) for row in read_rows(mmsi_run.run_dir / "results.jsonl")]
    assert hits == [bool(official) for _, official, _, _ in MMSI_REPLIES]


@pytest.mark.parametrize("rule", ["mmsi-official", "mmsi-lmms"])
def test_mmsi_accuracies_per_rule_are_the_hand_computed_ones(mmsi_run, rule):
    assert _values(rescore_run(mmsi_run.run_dir, rule).summary) == pytest.approx(MMSI_EXPECTED[rule], abs=1e-12)


def test_mmsi_read_as_vlmevalkit_reads_it_gives_vlmevalkit_s_numbers(tmp_path, mmsi_copy, offline_plugin_file, queued_backend):
    replies = [r for r, *_ in MMSI_REPLIES]
    result = _run(tmp_path, offline_plugin_file, queued_backend, mmsi_copy, "mmsi", replies, parser="vlmevalkit-spatial", scorer="choice-vlmevalkit")
    assert _values(result.summary, "choice-vlmevalkit") == pytest.approx(MMSI_EXPECTED["vlmevalkit-spatial"], abs=1e-12)


def test_omnispatial_is_read_by_its_own_re_rule_unless_told_otherwise(omni_run):
    assert yaml.safe_load((omni_run.run_dir / "config.yaml").read_text())["parser"]["name"] == "omnispatial-re"
    rows = read_rows(omni_run.run_dir / "results.jsonl")
    assert [row.scores.get("choice", {}).get("correct", False) for row in rows] == [bool(re) for _, re, *_ in OMNI_REPLIES]
    assert rows[0].parse.status == "repaired" and "reads it as A" in rows[0].parse.repair


@pytest.mark.parametrize("rule", OMNI_RULES)
def test_omnispatial_accuracies_per_rule_are_the_hand_computed_ones(omni_run, rule):
    values = _values(rescore_run(omni_run.run_dir, rule).summary)
    assert {k: values[k] for k in OMNI_EXPECTED[rule]} == pytest.approx(OMNI_EXPECTED[rule], abs=1e-12)


def test_omnispatial_hits_per_rule_are_the_ones_written_beside_each_reply(omni_run):
    for column, rule in enumerate(OMNI_RULES, start=1):
        rows = read_rows(rescore_run(omni_run.run_dir, rule).out_dir / "results.jsonl")
        assert [int(row.scores.get("choice", {}).get("correct", False)) for row in rows] == [reply[column] for reply in OMNI_REPLIES], rule


def test_the_report_breaks_perspective_taking_down_by_sub_task(omni_run, tmp_path):
    from povagent.report.build import write_report

    write_report(omni_run.run_dir, tmp_path / "report", gallery=False, n_boot=200)
    (system,) = json.loads((tmp_path / "report" / "summary.json").read_text())["metrics"]["choice"].values()
    per_category = {k: c["accuracy"]["value"] for k, c in system["per_category"].items()}
    expected = OMNI_EXPECTED["omnispatial-re"]
    assert {k: per_category[k] for k in (PT, EGO, ALLO, HYPO)} == pytest.approx({k: expected[k] for k in (PT, EGO, ALLO, HYPO)}, abs=1e-12)


def _oracle_run(tmp_path, path, plugin, parser):
    config = {"plugins": [str(plugin)], "dataset": {"path": str(path), "format": "omnispatial"}, "backend": "oracle", "parser": parser,
              "strategy": "choice", "runs": 1, "concurrency": 2, "timeout": 5, "output": str(tmp_path / f"oracle-{parser}")}  # fmt: skip
    (tmp_path / f"oracle-{parser}.yaml").write_text(yaml.safe_dump(config))
    return run_pipeline(load_pipeline(tmp_path / f"oracle-{parser}.yaml"))


def test_the_oracle_backend_s_bare_letters_check_omnispatial_s_wiring_read_directly(tmp_path, omni_copy, offline_plugin_file):
    assert _values(_oracle_run(tmp_path, omni_copy, offline_plugin_file, "omnispatial-direct").summary)["overall"] == 1.0


def test_the_set_s_re_rule_reads_the_oracle_s_bare_letters_as_a(tmp_path, omni_copy, offline_plugin_file):
    gold_a = sum(gold == 0 for *_, gold in OMNI_RECORDS) / len(OMNI_RECORDS)
    assert _values(_oracle_run(tmp_path, omni_copy, offline_plugin_file, "omnispatial-re").summary)["overall"] == pytest.approx(gold_a, abs=1e-12)
