"""An episode numbers views from 1, enforces its budget, and turns every call into an observation."""

from __future__ import annotations

import json

from povagent.exchange.messages import ToolCall


def call(name: str, k: int = 0, **arguments) -> ToolCall:
    return ToolCall(f"c{k}", name, json.dumps(arguments))


def test_views_are_numbered_from_one_across_turns_and_an_answer_names_one(make_episode):
    ep = make_episode()
    first = ep.handle([call("go_to_frame", frame=2)], turn=1)
    second = ep.handle([call("turn", degrees=10)], turn=2)
    assert (first[0].view, second[0].view) == (1, 2)
    ep.handle([call("answer", image="view 2", x=5, y=6)], turn=3)
    assert ep.answer is not None and ep.answer.camera == ep.views[1].camera
    assert ep.answer.camera.yaw == 70.0  # frame 2 faced 60 degrees, turned 10 to the right


def test_answer_is_not_counted_against_the_budget(make_episode):
    ep = make_episode(budget=1)
    ep.handle([call("turn", degrees=5), call("answer", k=1, image="view 1", x=1, y=1)], turn=1)
    assert ep.counts.actions == 1 and ep.answer is not None


def test_invalid_calls_are_typed_observations_counted_against_the_budget(make_episode):
    ep = make_episode(budget=3)
    out = ep.handle([call("fly"), call("go_to_frame", k=1, frame=9), ToolCall("c2", "turn", '{"degrees": NaN}')], turn=1)
    assert [o.text.split(":")[0] for o in out] == ["invalid call"] * 3
    assert ep.counts.invalid_calls == 3 and ep.budget_left == 0 and not ep.views


def test_a_400_digit_integer_in_a_call_is_an_invalid_call_not_a_crash(make_episode):
    ep = make_episode(budget=2)
    out = ep.handle([ToolCall("c0", "turn", '{"degrees": ' + "9" * 400 + "}")], turn=1)
    assert out[0].text.startswith("invalid call: turn: degrees must lie within")
    assert ep.counts.invalid_calls == 1 and ep.steps[0].valid is False and not ep.views


def test_a_hundred_calls_in_one_turn_run_only_the_budget_and_render_no_more(make_episode):
    ep = make_episode(budget=8)
    out = ep.handle([call("turn", k, degrees=1) for k in range(100)], turn=1)
    assert len(out) == 100 and len(ep.views) == 8
    assert ep.counts.actions == 8 and ep.counts.refused_over_budget == 92
    assert out[-1].text.startswith("not run: the budget of 8 actions is used up")


def test_an_answer_in_an_image_not_shown_is_invalid(make_episode):
    ep = make_episode()
    out = ep.handle([call("answer", image="view 1", x=1, y=1), call("answer", k=1, image="frame 3", x=1, y=1)], turn=1)
    assert all("was shown" in o.text for o in out) and ep.answer is None


def test_a_move_reports_how_far_it_got_and_a_blocked_one_is_counted(make_episode):
    ep = make_episode()
    out = ep.handle([call("move", forward=60, right=0)], turn=1)
    assert "stopped by a wall or furniture" in out[0].text and ep.counts.blocked_moves == 1
    assert ep.steps[0].blocked and ep.steps[0].pose is not None


def test_ask_returns_the_speaker_and_counts_a_question(make_episode):
    ep = make_episode()
    out = ep.handle([call("ask", question="What were you doing?")], turn=1)
    assert "sofa" in out[0].text and ep.counts.questions == 1 and out[0].view is None


def test_the_wall_clock_limit_ends_the_episode_and_later_calls_are_not_run(make_episode):
    now = [0.0]
    ep = make_episode(max_seconds=5.0, clock=lambda: now[0])
    ep.handle([call("turn", degrees=1)], turn=1)
    now[0] = 6.0
    out = ep.handle([call("turn", degrees=1)], turn=2)
    assert ep.done and "time limit" in ep.end and out[0].text == "not run: the episode has ended"
    assert len(ep.views) == 1


def test_the_record_keeps_each_action_its_arguments_as_sent_and_the_view_hash(make_episode):
    ep = make_episode()
    ep.handle([ToolCall("c0", "turn", '{"degrees":   30}')], turn=1)
    step = ep.record().steps[0]
    assert (step.action, step.arguments, step.view, step.sha256) == ("turn", '{"degrees":   30}', 1, ep.views[0].sha256)


def test_the_record_keeps_a_bounded_number_of_steps_and_counts_the_rest(make_episode):
    from povagent.active.live_episode import MAX_RECORDED_STEPS

    ep = make_episode(budget=1)
    for turn in range(1, 4):
        ep.handle([call("turn", k, degrees=1) for k in range(128)], turn=turn)
    record = ep.record()
    assert len(record.steps) == MAX_RECORDED_STEPS and record.steps_dropped == 3 * 128 - MAX_RECORDED_STEPS
