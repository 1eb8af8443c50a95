"""The simulated speaker: answers a model's ``ask`` from the pair's facts only, by template.

What it is for: in the active mode a model may ask the person who spoke. By default
(``speaker: stated``) the speaker knows what the Stated (B) sentence says (what they were doing,
at which furniture) in every condition, and which object they were facing (the anchor); anything
else gets "I can't say more." So in Inferred (A) one ``ask`` hands the model the Stated
sentence, and A nearly becomes B. ``speaker: condition`` keeps the speaker to the condition's
information: in A they quote the Inferred sentence (what they were doing, not where), in B the
Stated one with the furniture, in Given (C) the Given sentence. The answer depends only on the
question's words and the pair, never on a model, so runs are reproducible and an asked question
cannot leak the target's position. What it must not do: read anything but the house's own pair
file, or answer beyond those facts.
"""

from __future__ import annotations

import dataclasses
import json
import re
from dataclasses import dataclass
from pathlib import Path

from povagent.errors import DatasetError, ReadTargetError
from povagent.files.confined_read import read_regular

#: The answer to any question outside the speaker's facts.
CANNOT_SAY = "I can't say more."
#: The largest pair file read (a generated house's is a few tens of KB).
MAX_PAIR_FILE = 8 * 1024 * 1024

_WHERE = re.compile(r"\b(doing|did|where|sit|sitting|sat|stand|standing|stood|lying|lay|furniture|activity|position|located|place|seat|at which)\b")
_FACING = re.compile(r"\b(fac\w*|looking|look|toward\w*|direction|orient\w*|heading|front of you)\b")


#: What the speaker may tell (the strategy option ``speaker``): the Stated sentence and the
#: furniture in every condition, or only the condition's own information.
SPEAKER_KNOWLEDGE = ("stated", "condition")


@dataclass(frozen=True)
class PairFacts:
    """What the speaker knows: the Stated sentence, the observer's and the anchor's types, and
    (kept to a condition) the sentence quoted instead and whether they say where they were."""

    stated: str
    observer_type: str
    anchor_type: str
    #: The sentence quoted when asked what they were doing (``None``: the Stated one).
    quote: str | None = None
    #: Whether they name the furniture they were at (the Stated sentence's information).
    names_place: bool = True

    def answer(self, question: str) -> str:
        """The templated answer to ``question`` (lower-cased words decide which fact, if any)."""
        from povagent.generate.sentences import word_for  # the generator loads with the house anyway

        q = question.lower()
        parts = []
        if _WHERE.search(q):
            place = f"I was at the {word_for(self.observer_type)}. " if self.names_place else ""
            parts.append(f'{place}As I put it: "{self.stated if self.quote is None else self.quote}"')
        if _FACING.search(q):
            parts.append(f"I was facing the {word_for(self.anchor_type)}.")
        return " ".join(parts) if parts else CANNOT_SAY


def pair_facts(house_dir: Path, house_id: str, pair_id: str, direction: str, condition: str = "b", knowledge: str = "stated") -> PairFacts:
    """The speaker's facts for one pair, direction and condition (``a``, ``b``, ``c``), read from
    the house's pair file; ``knowledge`` is one of :data:`SPEAKER_KNOWLEDGE`."""
    path = Path(house_dir) / f"{house_id}.json"
    try:  # regular files only, bounded: a pipe or a device planted there is refused, never waited on
        pairs = json.loads(read_regular(path, MAX_PAIR_FILE, what="pair file").decode("utf-8"))
    except ReadTargetError as exc:
        raise DatasetError(str(exc)) from None
    except (OSError, ValueError) as exc:
        raise DatasetError(f"{path}: cannot be read ({type(exc).__name__})") from None
    for entry in pairs if isinstance(pairs, list) else []:
        if isinstance(entry, dict) and entry.get("pair_id") == pair_id:
            try:
                stated = _sentence(entry["stage5"][direction]["type_b"])
                observer = entry["object_observer"]["raw_metadata"]["objectType"]
                anchor = entry["object_landmark"]["raw_metadata"]["objectType"]
            except (KeyError, TypeError):
                raise DatasetError(f"{path}: pair {pair_id}: field stage5.{direction}.type_b or an objectType is missing") from None
            facts = PairFacts(stated, str(observer), str(anchor))
            if knowledge == "stated" or condition == "b":
                return facts
            field = ("stage5", "type_a") if condition == "a" else ("stage6", "type_c")
            try:
                quote = _sentence(entry[field[0]][direction][field[1]])
            except (KeyError, TypeError):
                raise DatasetError(f"{path}: pair {pair_id}: field {field[0]}.{direction}.{field[1]} is missing") from None
            return dataclasses.replace(facts, quote=quote, names_place=False)
    raise DatasetError(f"{path}: no pair {pair_id}")


def _sentence(value: object) -> str:
    """A sentence as the release stores it: a string, or an object holding ``sentence``."""
    return str(value.get("sentence", "")) if isinstance(value, dict) else str(value)
