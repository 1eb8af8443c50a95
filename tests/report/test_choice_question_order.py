"""The choice tables' bootstrap draws questions in id order, not in the order rows were written
(a run with several workers writes keys as they finish)."""

from __future__ import annotations

import random

from povagent.report.choice_tables import ChoiceAnswer, _accuracy_table, per_question


def _answers(n: int = 60) -> list[ChoiceAnswer]:
    draw = random.Random(7)
    return [
        ChoiceAnswer("sys", f"q{i:03d}", draw.random() < 0.6, "A", "A", "cat", "choice-letter")
        for i in range(n)
        for _ in range(2)  # two runs a question
    ]


def test_per_question_lists_questions_in_id_order_whatever_the_rows_order():
    answers = _answers()
    shuffled = answers[:]
    random.Random(3).shuffle(shuffled)
    assert list(per_question(shuffled)) == sorted({a.instance_id for a in answers})
    assert per_question(shuffled) == per_question(answers)


def test_the_accuracy_tables_interval_is_the_same_for_rows_in_any_order():
    answers = _answers()
    shuffled = answers[:]
    random.Random(5).shuffle(shuffled)
    table = _accuracy_table("choice", "choice", answers, ["sys"], "", 500, 0, set())
    again = _accuracy_table("choice", "choice", shuffled, ["sys"], "", 500, 0, set())
    cell, cell_again = table.rows[0].cells[-1], again.rows[0].cells[-1]
    assert cell.lo is not None and cell.lo < cell.value < cell.hi
    assert (cell.value, cell.lo, cell.hi) == (cell_again.value, cell_again.lo, cell_again.hi)
