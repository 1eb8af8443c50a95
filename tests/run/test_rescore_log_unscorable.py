"""``rescore_log``: a reply a rule's scorer cannot score is named, counted and left out of that
rule's figures, never dropped silently.

A VLMEvalKit VSI-Bench prediction file with counting questions whose gold is 0: the set's own code
(vision-x-nyu/thinking-in-space@51e089c3 ``vsibench_process_results``) and lmms-eval's divide by
the gold and stop on such a row when a number is read (``ZeroDivisionError``, run outside the
project); VLMEvalKit@e8e78f05's ``VsiBench.evaluate``, run on this very file, scores it with
``abs_dist_norm`` (``|pred - gold|``) and gives 42.0 (0.42: MRA 1, 0.1, 1, 0, 0).
"""

from __future__ import annotations

import pytest

from povagent.run.rescore_log import rescore_log

HEADER = '"index"\t"question"\t"candidates"\t"answer"\t"question_type"\t"prediction"\n'
ROWS = [("0", "0"), ("0", "0.5"), ("3", "3"), ("2", "N/A"), ("0", "none")]  # (gold, reply): rows 2-6 of the file


@pytest.fixture
def zero_gold_file(tmp_path):
    path = tmp_path / "VSI-Bench_preds.tsv"
    path.write_text(HEADER + "".join(f'"{k}"\t"q"\t""\t"{gold}"\t"object_counting"\t"{reply}"\n' for k, (gold, reply) in enumerate(ROWS)), encoding="utf-8")
    return path


def test_the_sets_rule_names_each_row_whose_gold_is_0_and_scores_the_rest(zero_gold_file):
    result = rescore_log(zero_gold_file, "vlmevalkit", "vsibench", n_boot=0)
    official = result.rules[0]
    assert official.rule == "vsibench"
    assert [line.split(": ")[1] for line in official.unscorable] == ["row 2.answer", "row 3.answer"]
    assert all("gold is 0" in line for line in official.unscorable)
    assert official.overall == pytest.approx(1 / 3)  # rows 4-6: 1, 0 (no number in "N/A"), 0 (no number read: upstream's worst case)
    assert official.metrics["unscorable"].value == pytest.approx(2 / 5) and official.metrics["unscorable"].n == 5


def test_lmms_evals_rule_names_them_too_and_vlmevalkits_scores_them_as_vlmevalkit_does(zero_gold_file):
    result = rescore_log(zero_gold_file, "vlmevalkit", "vsibench", n_boot=0)
    rules = {r.rule: r for r in result.rules}
    assert len(rules["vsibench-lmms"].unscorable) == 2
    assert rules["vlmevalkit-vsibench"].unscorable == []
    assert rules["vlmevalkit-vsibench"].overall == pytest.approx(0.42)


def test_the_command_prints_each_unscorable_row(zero_gold_file):
    from typer.testing import CliRunner

    from povagent.cli import app

    result = CliRunner().invoke(app, ["rescore-log", str(zero_gold_file), "--harness", "vlmevalkit", "--set", "vsibench"])
    assert result.exit_code == 0, result.output
    assert "unscorable: " in result.stderr and "row 2.answer: the gold is 0" in result.stderr
    assert "2 replies vsibench could not score (named above), left out of its figures" in result.stderr
