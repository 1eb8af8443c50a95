"""A parser or scorer that raises becomes row data, the same wherever it is called."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

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


class CountingParser(Parser):
    """Reads every reply as an answer, counting the replies it was handed."""

    def __init__(self, reads_text_alone: bool) -> None:
        self.reads_text_alone = reads_text_alone
        self.handed: list[str] = []

    def parse(self, text, spec):
        self.handed.append(text)
        return ParsedAnswer(status=ParseStatus.OK, choice=text[:1], span=text)


def test_a_parser_reading_the_text_alone_reads_a_short_reply_once_per_spec():
    other_spec = AnswerSpec(schema={}, width=64, height=64, n_frames=1, asks_frame=False)
    alone, each_time = CountingParser(reads_text_alone=True), CountingParser(reads_text_alone=False)
    for parser in (alone, each_time):
        first = parse_or_unparseable(parser, "B", SPEC)
        again = parse_or_unparseable(parser, "B", SPEC)
        assert first == again and first.choice == "B"
        parse_or_unparseable(parser, "B", other_spec)
        long_reply = "B" + " because" * 20
        parse_or_unparseable(parser, long_reply, SPEC)
        parse_or_unparseable(parser, long_reply, SPEC)
    assert alone.handed == ["B", "B", "B" + " because" * 20, "B" + " because" * 20]  # "B" once per spec; a long reply each time
    assert each_time.handed == ["B"] * 3 + ["B" + " because" * 20] * 2


def test_a_parse_shared_by_the_rows_of_a_repeated_reply_cannot_be_changed():
    parser = CountingParser(reads_text_alone=True)
    first, again = parse_or_unparseable(parser, "C", SPEC), parse_or_unparseable(parser, "C", SPEC)
    assert first is again  # one object for both rows: a change to it would reach the other row
    with pytest.raises(ValidationError):
        first.choice = "D"  # type: ignore[misc]
    assert again.choice == "C" and again.model_copy(update={"choice": "D"}).choice == "D"  # a changed parse is a new one


def test_a_raising_parser_reading_the_text_alone_raises_and_is_told_each_time():
    parser = RaisingParser()
    parser.reads_text_alone = True  # type: ignore[attr-defined]
    seen: list[BaseException] = []
    for _ in range(2):
        assert parse_or_unparseable(parser, "A", SPEC, seen.append).status is ParseStatus.UNPARSEABLE
    assert len(seen) == 2
