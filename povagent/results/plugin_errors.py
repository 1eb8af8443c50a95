"""A plugin's error as row data: a parser that raises gives an unparseable answer, a scorer that
raises gives ``{"error": ...}`` in the row's scores. Parsers and scorers must not raise; when one
does during a run, the row records it and the run goes on (a third-party plugin's bug never ends
a run). The runner and the official reading both go through here, so a row reads the same
whichever wrote it. (``rescore`` lets such an error stop it instead: it rewrites a finished
run, and keeps the previous rescore rather than write one with holes.)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable

from povagent.answers.spec import AnswerSpec, ParsedAnswer, unparseable

if TYPE_CHECKING:
    from povagent.dataset.instances import Instance
    from povagent.dataset.set_interface import EvaluationSet
    from povagent.interfaces import Parser, Scorer

#: The longest reply a parser is handed, in characters (about a megabyte). A longer one (a model
#: repeating itself to its token limit) is a non-response saying so, whatever the rule: every
#: built-in rule reads in time linear in the reply, so this bounds each parse to well under a
#: second, and a plugin's rule, whose cost nobody here knows, gets the same bound.
MAX_REPLY_CHARS = 1_000_000

#: Told of an exception a plugin raised (to log it with its traceback), before it becomes data.
OnError = Callable[[BaseException], None]


def error_text(exc: BaseException) -> str:
    """How a row names an exception: ``ValueError: bad box``."""
    return f"{type(exc).__name__}: {exc}"


def parse_or_unparseable(parser: Parser, text: str, spec: AnswerSpec, on_error: OnError | None = None) -> ParsedAnswer:
    """``parser.parse(text, spec)``; an exception is an unparseable answer saying so, and a reply
    longer than :data:`MAX_REPLY_CHARS` is one too, never handed to the parser."""
    if len(text) > MAX_REPLY_CHARS:
        return unparseable(f"the reply is {len(text)} characters, longer than the {MAX_REPLY_CHARS} a parser reads", span=text[:200])
    # a parser whose reading depends on the text and the spec alone (``reads_text_alone``: the
    # built-in rules) reads a short reply it has read before as it did then: a multiple-choice
    # run's replies repeat a few labels, each parsed once per spec instead of once per key
    kept = len(text) <= _MAX_KEPT_CHARS and getattr(parser, "reads_text_alone", False) is True
    if kept:
        key = (id(parser), text, id(spec))
        known = _READ.get(key)
        if known is not None and known[0] is parser and known[1] is spec:
            return known[2]
    try:
        parsed = parser.parse(text, spec)
    except Exception as exc:  # parsers must not raise; if one does, the answer is no answer
        if on_error is not None:
            on_error(exc)
        return unparseable(f"parser raised {error_text(exc)}")
    if kept:
        if len(_READ) >= _MAX_KEPT:
            _READ.clear()
        _READ[key] = (parser, spec, parsed)  # (holding both: their ids name them while kept)
    return parsed


#: Parses of short replies by parsers that read the text and the spec alone, by (parser, reply,
#: spec): a parse is a value nobody changes, so rows may share one. Bounded in entries and in
#: the length of a reply kept.
_READ: dict[tuple[int, str, int], tuple[Parser, AnswerSpec, ParsedAnswer]] = {}
_MAX_KEPT = 1024
_MAX_KEPT_CHARS = 64


def score_or_error(
    scorer: Scorer, instance: Instance, parse: ParsedAnswer, dataset: EvaluationSet | None, on_error: OnError | None = None
) -> dict[str, Any]:
    """``scorer.score(...)``; an exception is ``{"error": "<type>: <message>"}``."""
    try:
        return scorer.score(instance, parse, dataset)
    except Exception as exc:  # scorers must not raise; if one does, the row says which and why
        if on_error is not None:
            on_error(exc)
        return {"error": error_text(exc)}
