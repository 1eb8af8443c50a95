"""A parser or scorer that raises becomes row data, the same wherever it is called."""

from __future__ import annotations

from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus
from povagent.interfaces import Parser, Scorer
from povagent.results.plugin_errors import error_text, parse_or_unparseable, score_or_error

SPEC = AnswerSpec(schema={}, width=512, height=512, n_frames=1, asks_frame=False)


class RaisingParser(Parser):
    def parse(self, text, spec):
        raise ValueError("no digits")


class RaisingScorer(Scorer):
    def score(self, instance, answer, dataset):
        raise KeyError("gt")


def test_a_raising_parser_gives_an_unparseable_answer_naming_the_exception():
    seen: list[BaseException] = []
    parsed = parse_or_unparseable(RaisingParser(), "text", SPEC, seen.append)
    assert parsed.status is ParseStatus.UNPARSEABLE
    assert parsed.reason == "parser raised ValueError: no digits"
    assert [type(e) for e in seen] == [ValueError]


def test_a_raising_scorer_gives_an_error_entry_naming_the_exception():
    seen: list[BaseException] = []
    scores = score_or_error(RaisingScorer(), None, ParsedAnswer(status=ParseStatus.OK, x=1.0, y=2.0), None, seen.append)  # type: ignore[arg-type]
    assert scores == {"error": "KeyError: 'gt'"}
    assert len(seen) == 1


def test_an_exception_is_named_by_its_type_and_message():
    assert error_text(RuntimeError("boom")) == "RuntimeError: boom"
