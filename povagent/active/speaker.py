"""The simulated speaker: answers a model's ``ask`` from the pair's facts only, by template.

What it is for: in the active mode a model may ask the person who spoke. The speaker knows
what the Stated (B) sentence says (what they were doing, at which furniture) and which object
they were facing (the anchor); anything else gets "I can't say more." The answer depends only
on the question's words and the pair, never on a model, so runs are reproducible and an
asked question cannot leak the target's position. What it must not do: read anything but the
house's own pair file, or answer beyond those two facts.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path

from povagent.errors import DatasetError

#: The answer to any question outside the speaker's facts.
CANNOT_SAY = "I can't say more."
#: The largest pair file read (a generated house's is a few tens of KB).
MAX_PAIR_FILE = 8 * 1024 * 1024

_WHERE = re.compile(r"\b(doing|did|where|sit|sitting|sat|stand|standing|stood|lying|lay|furniture|activity|position|located|place|seat|at which)\b")
_FACING = re.compile(r"\b(fac\w*|looking|look|toward\w*|direction|orient\w*|heading|front of you)\b")


@dataclass(frozen=True)
class PairFacts:
    """What the speaker knows: the Stated sentence, the observer's and the anchor's types."""

    stated: str
    observer_type: str
    anchor_type: str

    def answer(self, question: str) -> str:
        """The templated answer to ``question`` (lower-cased words decide which fact, if any)."""
        from povagent.generate.sentences import word_for  # the generator loads with the house anyway

        q = question.lower()
        parts = []
        if _WHERE.search(q):
            parts.append(f'I was at the {word_for(self.observer_type)}. As I put it: "{self.stated}"')
        if _FACING.search(q):
            parts.append(f"I was facing the {word_for(self.anchor_type)}.")
        return " ".join(parts) if parts else CANNOT_SAY


def pair_facts(house_dir: Path, house_id: str, pair_id: str, direction: str) -> PairFacts:
    """The speaker's facts for one pair and direction, read from the house's pair file."""
    path = Path(house_dir) / f"{house_id}.json"
    try:
        if path.stat().st_size > MAX_PAIR_FILE:
            raise DatasetError(f"{path}: larger than {MAX_PAIR_FILE} bytes, not read")
        pairs = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise DatasetError(f"{path}: cannot be read ({type(exc).__name__})") from None
    for entry in pairs if isinstance(pairs, list) else []:
        if isinstance(entry, dict) and entry.get("pair_id") == pair_id:
            try:
                stated = entry["stage5"][direction]["type_b"]
                observer = entry["object_observer"]["raw_metadata"]["objectType"]
                anchor = entry["object_landmark"]["raw_metadata"]["objectType"]
            except (KeyError, TypeError):
                raise DatasetError(f"{path}: pair {pair_id}: field stage5.{direction}.type_b or an objectType is missing") from None
            if isinstance(stated, dict):
                stated = stated.get("sentence", "")
            return PairFacts(str(stated), str(observer), str(anchor))
    raise DatasetError(f"{path}: no pair {pair_id}")
