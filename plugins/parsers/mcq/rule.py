"""What every upstream-rule parser shares: a rule gives a label or no label, and the parser says which.

A rule parser reports the label its rule gives exactly, even a letter outside the question's
options (``E`` on a four-option question), because the harness scores that letter as it is: a
label no option carries is simply never the gold one. Without options (a point question) no
rule is applied, as the ``choice`` parser does.
"""

from __future__ import annotations

from typing import ClassVar

from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.interfaces import Parser


class RuleParser(Parser):
    """A parser applying one upstream rule; subclasses name it as :attr:`rule` or implement :meth:`label`."""

    answer_types = frozenset({"choice"})
    reads = ""
    beside_official = ""
    #: Why a reply with no label is not one (the rule's own word for it, e.g. VLMEvalKit's ``Z``).
    no_label_reason = "the rule reads no option label"
    #: Where the rule comes from, ``owner/repo@commit`` (:mod:`.upstream`).
    source: ClassVar[str] = ""
    #: Whose rule it is: a harness (``lmms-eval``, ``VLMEvalKit``) or the set's own code.
    harness: ClassVar[str] = ""
    #: ``(set, scorer)`` pairs: the sets (dataset format keys) ``harness`` reads with this rule,
    #: each with the scorer that counts its hits as the harness does: what ``povagent rescore-log``
    #: scores a log of the set with, beside the set's official rule. A set added later names its
    #: harness rules here.
    harness_sets: ClassVar[tuple[tuple[str, str], ...]] = ()
    #: The filter the rule applies to the reply itself before reading it, as its harness does
    #: (lmms-eval's reasoning-tag strip); ``""``: it reads the reply as written.
    harness_filter: ClassVar[str] = ""
    #: The rule, where it reads the reply alone (``staticmethod(rule)``): the label it gives, or ``None``.
    rule: ClassVar[staticmethod[[str], str | None] | None] = None
    #: The parse depends on the reply and the asked spec alone (nothing random, nothing kept
    #: between replies), so a reply read before may be read as it was then
    #: (:func:`~povagent.results.plugin_errors.parse_or_unparseable`); a subclass whose reading
    #: depends on anything else sets it ``False``.
    reads_text_alone: ClassVar[bool] = True

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The label the rule reads in ``text``, or ``None`` where it reads none."""
        rule = type(self).rule
        if rule is None:
            raise NotImplementedError
        return rule(text)

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The rule's label as a typed parse; never raises."""
        if not spec.choices:
            return unparseable("the question has no options")
        label = self.label(text or "", spec)
        if label is None:
            return unparseable(self.no_label_reason, span=(text or "")[:200] or None)
        return ParsedAnswer(status=ParseStatus.OK, choice=label, span=(text or "")[:200])
