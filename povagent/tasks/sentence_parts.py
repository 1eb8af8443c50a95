"""A generated sentence taken apart into the parts the generator built it from.

What it is for: a task that asks about the relation must not give it away, yet must word the
question per condition as the point task words its sentence (A: the activity that implies the
observer; B: the activity naming the observer; C: the relation alone, beside the observer's
view). The generator writes every sentence as ``<context> <relation phrase>.``, where the
relation phrase is one of the registry's phrases of the instance's direction with the anchor's
name in it (:func:`povagent.generate.sentences.relation_phrase`), and the context ends with the
target ("While replacing the bulb, I saw the book", "The book was"). Reading the sentence back
with those same phrases gives the context, the target's words and the anchor's name.

What it must not do: guess. A sentence the generator does not write (the public release's,
written by a VLM) is a :class:`SentenceShapeError`; the tasks run on generated sets.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from povagent.generate.sentences import SIGHTING_VERBS
from povagent.geometry.directions import spec_of


class SentenceShapeError(ValueError):
    """The sentence is not one the generator writes for its direction."""


@dataclass(frozen=True)
class SentenceParts:
    """``sentence == f"{context} {relation_prefix}{anchor}."``; ``target`` is named at the
    context's end (after the sighting verb, or as the C sentence's subject)."""

    context: str
    relation_prefix: str
    anchor: str
    target: str

    def with_anchor(self, anchor: str) -> str:
        """The sentence again, its anchor named ``anchor`` instead."""
        return f"{self.context} {self.relation_prefix}{anchor}."

    @property
    def observed(self) -> str:
        """The context as a sentence of its own, without the relation: ``While replacing the
        bulb, I saw the book.`` (a Given sentence's, ``The book was.``, says nothing)."""
        return f"{self.context}."


def _prefixes(direction: str) -> list[str]:
    """The registry's phrases of ``direction`` up to the anchor's name, longest first (``on the
    {anchor}`` must not take ``on the left side of the {anchor}``)."""
    spec = spec_of(direction)
    phrases = {p for p in (spec.sentence_phrase, spec.on_anchor_phrase, spec.seat_phrase) if p is not None}
    return sorted((p.split("{anchor}")[0] for p in phrases), key=len, reverse=True)


_GIVEN = re.compile(r"The (?P<target>.+) (?:was|were)")
_SIGHTED = re.compile(rf".* I (?:{'|'.join(SIGHTING_VERBS)}) the (?P<target>.+)")


def sentence_parts(sentence: str, direction: str) -> SentenceParts:
    """The parts of a generated sentence of ``direction`` (a :class:`SentenceShapeError` when it
    is not one the generator writes)."""
    if not sentence.endswith("."):
        raise SentenceShapeError("it does not end in a full stop")
    body = sentence[:-1]
    for prefix in _prefixes(direction):
        at = body.rfind(f" {prefix}")
        if at < 0:
            continue
        context, anchor = body[:at], body[at + 1 + len(prefix) :]
        match = _GIVEN.fullmatch(context) or _SIGHTED.fullmatch(context)
        if match is None or not anchor:
            continue
        return SentenceParts(context, prefix, anchor, match["target"])
    raise SentenceShapeError(f"no relation phrase of {direction!r} as the generator writes it")
