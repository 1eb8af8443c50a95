"""Reasoning traces for the generated multiple-choice tasks (relation, multi-hop), from the scene.

The point task's trace (:mod:`povagent.train.rationale`) ends in a pixel; a choice task's ends
in the option's label, as the ``choice`` prompt asks (``{"choice": "B"}``, which the ``choice``
parser reads by its rule 2). The steps say where the speaker stood and which way they faced
(the same :class:`~povagent.tasks.scene_facts.InstanceFacts` the point trace states), the target's
relation to the anchor from there, then, for a multi-hop question, the hop through the
intermediate object (:class:`~povagent.tasks.multi_hop.Hop`, from the house's object boxes),
and last the option whose words name the relation. ``none`` is the bare answer; ``cot`` and
``s-cot`` give the steps (a Given instance, whose image is the speaker's own view, starts at
the relation).

Every fact comes from the facts or the hop; the template adds no geometry of its own.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING

from povagent.answers.choice_question import ChoiceQuestion
from povagent.geometry.directions import spec_of
from povagent.tasks.scene_facts import InstanceFacts
from povagent.train.rationale import RATIONALES, stood_phrase, turned_phrase

if TYPE_CHECKING:  # the generator's scene loads only when a task asks
    from povagent.tasks.multi_hop import Hop


def _words(name: str) -> str:
    """``CoffeeTable`` -> ``coffee table``."""
    return "".join(f" {c.lower()}" if c.isupper() and i else c.lower() for i, c in enumerate(name))


def choice_answer_json(question: ChoiceQuestion) -> str:
    """The answer line: ``{"choice": "B"}`` (the gold label)."""
    return json.dumps({"choice": question.gold})


def choice_rationale_text(facts: InstanceFacts, question: ChoiceQuestion, kind: str, hop: Hop | None = None) -> str:
    """The assistant's whole answer to ``question``: the steps of ``kind``, then the JSON line."""
    if kind not in RATIONALES:
        raise ValueError(f"rationale must be one of {', '.join(RATIONALES)}, not {kind!r}")
    answer = choice_answer_json(question)
    if kind == "none":
        return answer
    obs, anc = _words(facts.observer_type), _words(facts.anchor_type)
    relation = spec_of(facts.direction).paper_words
    lines = []
    if facts.frame_index is not None:
        lines.append(
            f"Observer: in Image {facts.frame_index} the speaker, at the {obs}, {stood_phrase(facts)}; "
            f"facing the {anc} from there, they are {turned_phrase(facts)}, looking {facts.facing}."
        )
    else:
        lines.append(f"Observer: the image is the speaker's own view, facing the {anc}.")
    lines.append(f"Relation: from there the target is {relation} the {anc}, {facts.surface}.")
    named = spec_of(facts.direction)
    if hop is not None:
        link = spec_of(hop.link)
        named = spec_of(hop.gold)
        lines.append(
            f"Intermediate: the {hop.name} stands {link.paper_words} the {anc} from the same place, so the target is {named.paper_words} the {hop.name}."
        )
    label = next(lab for lab, text in question.options if text == named.short_words)
    lines.append(f"Conclusion: {named.short_words}, option {label}.")
    return "\n\n".join(lines) + "\n" + answer
