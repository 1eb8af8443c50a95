"""Every parser of the choice sets reads a reply of up to the bound (a megabyte) in well under a
second of CPU, whatever it holds; a longer reply is never handed to a parser."""

from __future__ import annotations

import time

import pytest

from povagent.answers.spec import ParseStatus
from povagent.plugins import get_plugin_host
from povagent.results.plugin_errors import MAX_REPLY_CHARS, parse_or_unparseable

from .mcq_corpus import choice_spec, read_with

#: a quadratic strip of a megabyte takes hours: the bound ends the test instead
pytestmark = pytest.mark.timeout(120)

CHOICE_SET_PARSERS = ["choice", "viewspatial", "mindcube", "3dsrbench-lmms", "vlmevalkit-exact", "vlmevalkit-spatial",
                      "lmms-mcq-extract", "sparbench-lmms"]  # fmt: skip
N = MAX_REPLY_CHARS
HOSTILE = {
    "unclosed-think-tags": "<think>" * (N // 7),  # the choice parser's strip took 177 s on 280 KB
    "think-tags-and-text": "<think>x" * (N // 8),
    "unclosed-analysis-tags": "<analysis>" * (N // 10),
    "labels-with-periods": "A. " * (N // 3),
    "answer-sections": "<Answer>A " * (N // 10),
    "json-openings": '{"choice": ' * (N // 11),
}


@pytest.mark.parametrize("parser", CHOICE_SET_PARSERS)
@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_a_megabyte_reply_is_read_in_well_under_a_second(parser, case):
    read_with(parser, "B")  # the plugin host is built outside the timed part
    start = time.process_time()  # this process's CPU time: immune to a loaded machine
    read_with(parser, HOSTILE[case])
    assert time.process_time() - start < 1.5


def test_the_choice_parser_still_drops_complete_blocks_and_reads_after_a_dangling_close():
    assert read_with("choice", "<think>A</think><think>x<think>C</think>B").choice == "B"
    assert read_with("choice", "A, or maybe </think> C").choice == "C"
    assert read_with("choice", "<think> unclosed B").choice is None  # the tag stays, so the last line opens with it


def test_a_reply_past_the_bound_is_a_non_response_the_parser_never_sees():
    class Counting:
        calls = 0

        def parse(self, text, spec):
            Counting.calls += 1
            return get_plugin_host(()).parser("choice", {}).parse(text, spec)

    parsed = parse_or_unparseable(Counting(), "B" + " " * MAX_REPLY_CHARS, choice_spec())  # type: ignore[arg-type]
    assert parsed.status == ParseStatus.UNPARSEABLE and "longer than" in (parsed.reason or "") and Counting.calls == 0
    assert parse_or_unparseable(Counting(), "B", choice_spec()).choice == "B" and Counting.calls == 1  # type: ignore[arg-type]
