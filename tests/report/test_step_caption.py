"""How an active step is captioned under its trajectory (povagent/report/step_caption.py): every
number rounded by one rule, and nothing cut short without an ellipsis."""

from __future__ import annotations

import pytest

from povagent.report.step_caption import ELLIPSIS, MAX_CAPTION, caption_number, step_caption


@pytest.mark.parametrize(
    ("value", "shown"),
    [(255.999, "256"), (-0.4656, "-0.47"), (10.0, "10"), (0.004, "0"), (-0.004, "0"), (1.5, "1.5"), (323.45, "323.45")],
)
def test_a_number_is_rounded_to_two_decimals_with_trailing_zeros_dropped(value, shown):
    assert caption_number(value) == shown


def test_a_move_shows_both_arguments_rounded_never_a_key_without_its_value():
    assert step_caption("move", '{"forward": 1.1432, "right": -0.4656}') == "move(forward=1.14, right=-0.47)"


def test_an_answer_rounds_its_pixel_instead_of_cutting_its_digits():
    assert step_caption("answer", '{"image": "view 4", "x": 323.4, "y": 255.999}') == 'answer(image="view 4", x=323.4, y=256)'


def test_integers_stay_whole():
    assert step_caption("go_to_frame", '{"frame": 3}') == "go_to_frame(frame=3)"


def test_arguments_that_do_not_fit_are_left_out_whole_behind_an_ellipsis():
    caption = step_caption("answer", '{"image": "view 12", "x": 323.4567, "y": 255.999, "note": "a long remark here"}', limit=44)
    assert caption == f'answer(image="view 12", x=323.46, y=256, {ELLIPSIS})'
    assert len(caption) <= 44


def test_a_long_question_is_cut_with_an_ellipsis_inside_its_quotes():
    caption = step_caption("ask", '{"question": "What were you doing when you saw it, and where were you standing?"}')
    assert caption.startswith('ask(question="What were you doing') and caption.endswith(f'{ELLIPSIS}")')
    assert len(caption) <= MAX_CAPTION


def test_malformed_arguments_are_shown_as_sent_and_cut_with_an_ellipsis():
    assert step_caption("turn", "not json") == "turn(not json)"
    long = step_caption("turn", "x" * 500)
    assert len(long) == MAX_CAPTION and long.endswith(ELLIPSIS)


def test_non_finite_numbers_a_model_sent_are_named_not_hidden():
    assert step_caption("tilt", '{"degrees": NaN}') == "tilt(degrees=nan)"
