"""``rescore_log``: VLMEvalKit's rules read a reply as VLMEvalKit's own ``load`` hands it over, on
every set they apply to; the set's own rules and lmms-eval's read it as written.

The files in ``tests/fixtures/harness_logs/pandas_missing/`` (see the README there) hold, per set,
31 replies: each of pandas' 19 default missing-value strings (``N/A``, ``NA``, ``None``, ``NULL``,
``nan``, an empty cell...) with the gold ``A``, then near misses pandas keeps as text (``" N/A"``,
``"none"``, ``"NAN"``, ``"N/A."``) and ordinary replies. The expected VLMEvalKit figures were
produced by RUNNING VLMEvalKit's scoring on the files themselves, outside the project, at
open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94: ``vlmeval.smp.load``,
``eval_mcq_score`` with ``build_mcq_score_fn()`` (no judge: ``compute_mcq_score``) grouped as each
set's ``evaluate`` groups it, and for 3DSRBench ``_3DSRBench.evaluate``'s preparation then
``eval_vanilla(None, item)`` (exact matching). Before this reading, VLMEvalKit's spatial rule read
``"N/A"``, ``"NA"``, ``"#N/A"``... as ``A`` here (9/31 on each spatial file), and its exact rule read
``"None"`` as the option ``no`` and an option cell ``"None"`` as a choice (6/33 on 3DSRBench's).
"""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest

from povagent.run.rescore_log import rescore_log

FILES = Path(__file__).resolve().parent.parent / "fixtures" / "harness_logs" / "pandas_missing"
VS_CAM, VS_PER = "Camera perspective - Relative Direction", "Person perspective - Relative Direction"

# (file, set, VLMEvalKit's rule, its overall, its per-category cells), as VLMEvalKit's own functions give them
VLMEVALKIT = [
    ("ViewSpatialBench_missing_preds.tsv", "viewspatial", "vlmevalkit-spatial", "6/31", {VS_CAM: "1/16", VS_PER: "1/3"}),
    ("ViewSpatialBench_missing_preds.xlsx", "viewspatial", "vlmevalkit-spatial", "6/31", {VS_CAM: "1/16", VS_PER: "1/3"}),
    ("MindCubeBench_missing_preds.tsv", "mindcube", "vlmevalkit-spatial", "6/31", {"among": "1/11", "around": "1/5", "rotation": "3/10"}),
    ("MMSIBench_wo_circular_missing_preds.tsv", "mmsi", "vlmevalkit-spatial", "6/31", {"Pos-Cam-Cam": "1/11", "Attr-Meas": "1/5", "MSR": "3/10"}),
    (
        "OmniSpatialBench_manual_cot_missing_preds.tsv",
        "omnispatial",
        "vlmevalkit-spatial",
        "6/31",
        {"Dynamic_Reasoning": "1/16", "Manipulation": "1/16", "Perspective_Taking": "1/3", "Egocentric": "1/3"},
    ),
    ("3DSRBench_missing_preds.tsv", "3dsrbench", "vlmevalkit-exact", "4/33", {"height_higher": "1/5", "location_above": "1/18"}),
]
#: The replies pandas reads as missing, in the files' order (their first 19 rows).
MISSING = [
    "",
    "#N/A",
    "#N/A N/A",
    "#NA",
    "-1.#IND",
    "-1.#QNAN",
    "-NaN",
    "-nan",
    "1.#IND",
    "1.#QNAN",
    "<NA>",
    "N/A",
    "NA",
    "NULL",
    "NaN",
    "None",
    "n/a",
    "nan",
    "null",
]


def _fraction(value: str) -> float:
    return float(Fraction(value))


@pytest.mark.parametrize(("name", "set_name", "rule", "overall", "per_category"), VLMEVALKIT, ids=[row[0] for row in VLMEVALKIT])
def test_vlmevalkits_rule_gives_what_vlmevalkits_own_scoring_gives_on_replies_pandas_reads_as_missing(name, set_name, rule, overall, per_category):
    result = rescore_log(FILES / name, "vlmevalkit", set_name, n_boot=0)
    assert (result.items, result.bad_records) == (31 if set_name != "3dsrbench" else 33, 0)
    got = next(r for r in result.rules if r.rule == rule)
    assert got.metrics["accuracy" if rule != "vlmevalkit-exact" else "vanilla_accuracy"].value == pytest.approx(_fraction(overall), abs=1e-12)
    assert got.per_category == pytest.approx({c: _fraction(v) for c, v in per_category.items()}, abs=1e-12)


@pytest.mark.parametrize(("name", "set_name", "rule"), [(row[0], row[1], row[2]) for row in VLMEVALKIT], ids=[row[0] for row in VLMEVALKIT])
def test_vlmevalkits_rule_reads_no_option_in_a_reply_pandas_reads_as_missing_and_says_why(name, set_name, rule):
    result = rescore_log(FILES / name, "vlmevalkit", set_name, n_boot=0)
    read = {d.item: d.labels[rule] for d in result.disagreements}
    # every missing reply another rule reads a letter in ("N/A", "NA", "#N/A"...) is one VLMEvalKit's reads nothing in
    assert all(read[item] is None for item in read if int(item) < len(MISSING))
    assert "VLMEvalKit's load" in next(r.reads for r in result.rules if r.rule == rule)


def test_the_sets_own_rule_and_lmms_evals_still_read_n_a_as_written():
    result = rescore_log(FILES / "ViewSpatialBench_missing_preds.tsv", "vlmevalkit", "viewspatial", n_boot=0)
    na = next(d for d in result.disagreements if d.reply == "N/A")  # row 12: gold A
    assert na.labels == {"viewspatial-official": "A", "viewspatial": "A", "vlmevalkit-spatial": None}
    assert na.correct == {"viewspatial-official": True, "viewspatial": True, "vlmevalkit-spatial": False}
    assert {r.rule: r.overall for r in result.rules if not r.rule.startswith("vlmevalkit")} == pytest.approx(
        {"viewspatial-official": 10 / 31, "viewspatial": 10 / 31}
    )

