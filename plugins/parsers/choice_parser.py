"""The ``choice`` parser: povagent's own reading of a multiple-choice answer.

One rule, stated so a reader can predict it (the sets' official rules and the harnesses' rules
are separate, named parsers):

1. Complete ``<think>...</think>`` blocks are removed, and everything up to a ``</think>`` left
   without its opening tag.
2. A JSON object with a ``choice`` (or ``answer``) key whose value starts with an option label
   (``"B"``, ``"B. left"``) gives that label.
3. Else the last non-empty line, with markdown emphasis and a leading ``Answer:``, ``Final
   answer:`` or ``The answer is`` removed, must start with an option label standing alone
   (``B``, ``(B)``, ``B.``, ``B)``, ``B: left``) and name no other label standing alone
   (``A or B`` is no answer); a line such as ``Because...`` is no label.
4. Else, when that line is exactly one option's text (case and a final period aside), that
   option; the parse is then ``repaired`` (read from the text, not a label).

Anything else is a non-response. Labels are matched as the options write them (case-sensitive).
Never raises.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, unparseable
from povagent.answers.text import find_objects, get_key
from povagent.interfaces import Parser

_LEAD = re.compile(r"^(?:final\s+answer|answer|the\s+(?:correct\s+)?answer\s+is)\s*[:\-]?\s*", re.IGNORECASE)
_LABEL = re.compile(r"^\(?([A-Za-z0-9]{1,3})(?:\)|\.|:|\s|$)")


def without_reasoning(text: str) -> str:
    """``text`` without complete ``<think>`` blocks, and after a ``</think>`` left unopened.

    A block runs from a ``<think>`` to the first ``</think>`` after it; the search goes on after
    it. One pass: no character is looked at twice (a regular expression's lazy block took time
    quadratic in the number of unclosed ``<think>`` tags: minutes on a 280 KB reply)."""
    kept: list[str] = []
    pos = 0
    while (start := text.find("<think>", pos)) != -1:
        end = text.find("</think>", start + len("<think>"))
        if end == -1:  # no later <think> can close either
            break
        kept.append(text[pos:start])
        pos = end + len("</think>")
    text = "".join(kept) + text[pos:]
    if "</think>" in text:
        text = text.rsplit("</think>", 1)[1]
    return text.strip()


def _label_at_start(value: str, labels: tuple[str, ...]) -> str | None:
    """The label opening ``value``, unless the rest of it names another label standing alone."""
    match = _LABEL.match(value.strip())
    if not match or match.group(1) not in labels:
        return None
    rest = value.strip()[match.end() :]
    others = (lab for lab in labels if lab != match.group(1))
    if any(re.search(rf"(?<![A-Za-z0-9]){re.escape(lab)}(?![A-Za-z0-9])", rest) for lab in others):
        return None
    return match.group(1)


class ChoiceParser(Parser):
    """The rule in the module docstring (no options)."""

    answer_types = frozenset({"choice"})
    #: What it reads, and how that compares with the ``official`` reading (the parser tables
    #: of the docs are generated from these).
    reads = "a multiple-choice label: a JSON `choice`, else a label opening the last line, else one option's text"
    beside_official = "reads choice answers, which the official (point) parser does not read; the sets' official rules are their own parsers"

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The option ``text`` chooses among ``spec.choices``; never raises."""
        labels = tuple(label for label, _ in spec.choices)
        if not labels:
            return unparseable("the question has no options")
        body = without_reasoning(text or "")
        for obj in reversed(find_objects(body)):
            for key in ("choice", "answer"):
                present, value = get_key(obj.value, key)
                if present and isinstance(value, str) and (label := _label_at_start(value, labels)):
                    return ParsedAnswer(status=ParseStatus.OK, choice=label, span=obj.span)
        lines = [line.strip() for line in body.splitlines() if line.strip()]
        if not lines:
            return unparseable("empty answer")
        last = _LEAD.sub("", lines[-1].replace("*", "").replace("_", "").replace("`", "").strip())
        if label := _label_at_start(last, labels):
            return ParsedAnswer(status=ParseStatus.OK, choice=label, span=lines[-1])
        said = last.rstrip(".").strip().casefold()
        named = [label for label, option in spec.choices if option.strip().rstrip(".").casefold() == said]
        if len(named) == 1:
            return ParsedAnswer(status=ParseStatus.REPAIRED, choice=named[0], span=lines[-1], repair="option read from its text")
        return unparseable("no option label on the last line", span=lines[-1][:200])


@hookimpl
def register_parsers(register) -> None:
    """Contribute the choice parser."""
    register("choice", ChoiceParser, description="Multiple choice: a JSON choice, else a label opening the last line, else an option's text")
