"""The report's manual assessment: judged success per system and condition with Wilson
intervals, and Cohen's kappa where two judges judged the same predictions."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from povagent.report.manual import cohen_kappa, manual_tables, wilson
from povagent.results.judgements import Judgement, JudgementJournal, judged_item, run_identity


def prediction(x=1.0):
    return SimpleNamespace(selected_image=0, x=x, y=2.0)


def a_run(folder, items=tuple(f"i{k}" for k in range(8)), config="output: run\n"):
    """A run folder's identity and rows, as a report holds them: rows keyed ``<item>#0``."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "config.yaml").write_text(config)
    return SimpleNamespace(folder=folder, rows=[SimpleNamespace(key=f"{i}#0", prediction=prediction()) for i in items])


def item(run, name):
    """The judged item of row ``<name>#0`` of ``run``."""
    return judged_item(run_identity(run.folder), f"{name}#0", prediction())


RUN = None  # set by the autouse fixture: the run every judgement below judges


@pytest.fixture(autouse=True)
def the_run(tmp_path):
    global RUN
    RUN = a_run(tmp_path / "run")
    yield RUN
    RUN = None


def judgement(judge, name, verdict, system="model-a", condition="A", run=None):
    return Judgement(item=item(run or RUN, name), judge=judge, verdict=verdict, seconds=1.0, system=system, run_name=system,
                     key=f"{name}#0", instance_id=name, condition=condition)  # fmt: skip


def write(folder, judgements):
    for j in judgements:
        JudgementJournal(folder, j.judge).append(j)


def test_wilson_interval_matches_the_textbook_value():
    cell = wilson(8, 10)  # 0.8 of 10: 95% Wilson interval 0.490 .. 0.943
    assert cell.value == pytest.approx(0.8)
    assert (cell.lo, cell.hi) == (pytest.approx(0.4902, abs=1e-4), pytest.approx(0.9433, abs=1e-4))


def test_no_judgement_gives_no_rate():
    assert wilson(0, 0).value is None


def test_cohen_kappa_of_a_worked_example():
    # 10 items: both say success on 4, both failure on 3, they differ on 3 -> po 0.7, pe 0.5, kappa 0.4
    a = ["success"] * 4 + ["failure"] * 3 + ["success", "success", "failure"]
    b = ["success"] * 4 + ["failure"] * 3 + ["failure", "failure", "success"]
    assert cohen_kappa(a, b) == pytest.approx((0.7 - 0.5) / 0.5)


def test_cohen_kappa_is_undefined_when_both_judges_never_vary():
    assert cohen_kappa(["success"] * 3, ["success"] * 3) is None


def test_a_source_without_judgements_gets_no_manual_table(tmp_path):
    assert manual_tables(tmp_path / "run", [RUN]) == []


def test_the_success_table_counts_cant_tell_in_neither_rate_nor_denominator(tmp_path):
    write(tmp_path / "judgements", [
        judgement("carol", "i1", "success"), judgement("carol", "i2", "failure"), judgement("carol", "i3", "cant_tell"),
        judgement("carol", "i4", "success", condition="C"), judgement("carol", "i5", "success", system="human:alice"),
    ])  # fmt: skip
    table = manual_tables(tmp_path / "run", [RUN])[0]
    assert [c.name for c in table.columns] == ["A", "C", "All", "Judged", "Can't tell"]
    rows = {r.label: [c.value for c in r.cells] for r in table.rows}
    assert rows["model-a"] == [pytest.approx(0.5), 1.0, pytest.approx(2 / 3), 3.0, 1.0]
    assert rows["human:alice"][0] == 1.0


def test_agreement_is_shown_only_where_two_judges_overlap(tmp_path):
    write(tmp_path / "judgements", [judgement("carol", "i1", "success"), judgement("dave", "i2", "success")])
    assert [t.key for t in manual_tables(tmp_path / "run", [RUN])] == ["manual_success"]


def test_two_judges_on_the_same_predictions_get_their_agreement_and_kappa(tmp_path):
    verdicts = [("success", "success"), ("failure", "failure"), ("success", "failure"), ("cant_tell", "cant_tell")]
    write(tmp_path / "judgements", [judgement(j, f"i{k}", v[n]) for k, v in enumerate(verdicts) for n, j in enumerate(("carol", "dave"))])
    agreement = manual_tables(tmp_path / "run", [RUN])[1]
    (row,) = agreement.rows
    assert row.label == "carol / dave"
    assert [c.value for c in row.cells] == [4.0, 0.75, pytest.approx(cohen_kappa([v[0] for v in verdicts], [v[1] for v in verdicts]))]


def test_a_torn_last_line_is_skipped_and_the_next_judgement_stands_alone(tmp_path):
    folder = tmp_path / "judgements"
    write(folder, [judgement("carol", "i1", "success")])
    with open(folder / "carol.jsonl", "ab") as f:
        f.write(b'{"item": "' + item(RUN, "i2").encode() + b'", "judge": "ca')  # a kill mid-write
    JudgementJournal(folder, "carol").append(judgement("carol", "i3", "failure"))
    (row,) = manual_tables(tmp_path / "run", [RUN])[0].rows
    assert row.cells[-2].value == 2.0


def test_judgements_of_another_run_with_the_same_cell_name_are_left_out(tmp_path):
    # two sweeps, each with a cell named "a" holding the same row keys; carol judged sweep X only
    x = a_run(tmp_path / "sweep-x" / "a", config="output: sweep-x/a\n")
    y = a_run(tmp_path / "sweep-y" / "a", config="output: sweep-y/a\n")
    write(tmp_path / "judgements", [judgement("carol", "i1", "success", run=x), judgement("carol", "i2", "failure", run=x)])
    assert manual_tables(tmp_path / "sweep-y", [y]) == []  # nobody judged Y: no table
    (row,) = manual_tables(tmp_path / "sweep-x", [x])[0].rows
    assert row.cells[-2].value == 2.0


def test_a_run_redone_in_place_with_another_answer_is_not_the_judged_one(tmp_path):
    write(tmp_path / "judgements", [judgement("carol", "i1", "success")])
    redone = SimpleNamespace(folder=RUN.folder, rows=[SimpleNamespace(key="i1#0", prediction=prediction(x=9.0))])
    assert manual_tables(tmp_path / "run", [redone]) == []
