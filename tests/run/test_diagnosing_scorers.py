"""The summary's diagnostics read the scorers that declare a diagnosis (``Scorer.diagnosis``),
whatever their names: a third-party relation scorer's hits are counted as the built-in's are."""

from __future__ import annotations

from povagent import hookimpl
from povagent.interfaces import Scorer
from povagent.results.rows import ResultRow, RowStatus
from povagent.run.summary_fields import diagnosed_row
from povagent.scoring.score_protocols import diagnosing_scorers


class RegionHit(Scorer):
    diagnosis = "relation_hit"

    def score(self, instance, answer, dataset=None):
        return {"answered": True, "success": True}


class RegionPlugin:
    @hookimpl
    def register_scorers(self, register):
        register("a-region-hit", RegionHit, description="test: a relation hit under another name")


def row(scores: dict) -> ResultRow:
    return ResultRow(key="h/p/left/a#0", instance_id="h/p/left/a", house_id="h", pair_id="p", direction="left",
                     condition="a", status=RowStatus.ANSWERED, scores=scores)  # fmt: skip


def test_the_built_in_scorers_declare_the_two_diagnoses():
    assert diagnosing_scorers() == {"failure_step": "diagnose", "relation_hit": "relation"}


def test_a_third_party_scorer_declaring_a_diagnosis_is_read_by_the_summary(povagent_host):
    povagent_host.add_plugin(RegionPlugin(), name="region-plugin")
    try:
        assert diagnosing_scorers()["relation_hit"] == "a-region-hit"  # sorted by name: it comes first
        diagnosed = diagnosed_row(row({"a-region-hit": {"answered": True, "success": True}}), None)
    finally:
        povagent_host.remove_plugin("region-plugin")
    assert diagnosed is not None and diagnosed.relation is True
    assert diagnosed_row(row({"a-region-hit": {"answered": True, "success": True}}), None) is None  # gone with its plugin
