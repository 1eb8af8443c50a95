"""A hostile reply costs every upstream-rule parser time linear in its length, and never raises.

The upstream patterns backtrack for minutes on long runs of spaces or markdown (VLMEvalKit's
concluding-phrase pattern in cubic time), and lmms-eval's reasoning strip copies the reply once
per block; the parsers read the same labels (the probe corpus holds them equal) in linear time.
"""

from __future__ import annotations

import time

import pytest

from povagent.answers.spec import ParsedAnswer

from .mcq_corpus import read_with

RULE_PARSERS = ["viewspatial", "mindcube", "3dsrbench-lmms", "vlmevalkit-exact", "vlmevalkit-spatial", "lmms-mcq-extract",
                "lmms-mcq-extract-corrected", "sparbench-lmms", "sparbench-lmms-corrected"]  # fmt: skip
N = 200_000
SPACES = " " * N
HOSTILE = {
    "phrase-then-spaces": "answer" + SPACES + "x",
    "letter-then-spaces": "A" + SPACES + "x",
    "spaces-inside-a-line": "x" + SPACES + "x",
    "markdown-run": "x" + "*" * N + "x",
    "tabs-and-newlines": "x" + "\t\n" * (N // 2) + "x",
    "unclosed-answer-tags": "<answer" * (N // 7) + ">" + SPACES + "x",
    "answer-tags-never-closed": "<answer>A" * (N // 9),
    "many-reasoning-blocks": "<think></think>x" * (1_000_000 // 16),  # a copy per block took seconds
    "correct-answer-is-spaced": "correct" + SPACES + "answer" + SPACES + "is" + SPACES + "x",
}


@pytest.mark.parametrize("parser", RULE_PARSERS)
@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_hostile_reply_is_read_in_linear_time(parser, case):
    read_with(parser, "B")  # the plugin host is built outside the timed part
    start = time.process_time()  # this process's CPU time: immune to a loaded machine
    parsed = read_with(parser, HOSTILE[case])
    assert isinstance(parsed, ParsedAnswer)
    assert time.process_time() - start < 1.0  # the upstream forms took seconds to hours here
