"""lmms-eval's reasoning strip, the step every lmms-eval rule starts from (expected texts are what
lmms-eval's ``strip_reasoning_tags`` returns at the pinned commit for each input)."""

from __future__ import annotations

import pytest

from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks


@pytest.mark.parametrize(
    ("reply", "left"),
    [
        ("<think>a</think>B", "B"),
        ("reasoning with no opening tag</think>\nB", "B"),
        ("<think>a</think><think>b", "<think>b"),  # an opening tag never closed stays
        ("a</think>b<think>c", "a</think>b<think>c"),  # a closing tag before the only opening tag: nothing removed
        ("<thi<think>x</think>nk>y</think>B", "B"),  # the removal completes a new opening tag, removed too
        ("<analysis>x</analysis>A</think>B", "B"),
        ("<think>x</think>\n<analysis>y</analysis>C", "C"),
        ("<THINK>x</THINK>B", "<THINK>x</THINK>B"),  # tags match case-sensitively
    ],
)
def test_strips_reasoning_as_lmms_eval_does(reply, left):
    assert strip_reasoning_blocks(reply) == left
