"""A question answered with a number: the question as asked, its gold value and the value's unit.

What an instance carries when it asks for a ``number`` answer (``Instance.numeric``): VSI-Bench's
numerical-answer questions (object counts, distances in meters, sizes in centimeters, room
areas in square meters). ``unit`` is the unit the gold value is in where the set says so (empty:
a count, or a set that does not say); ``category`` is the set's question type, the slice scores
are broken down by.

Pure values: nothing here reads files or parses answers.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class NumericQuestion:
    """One question with a gold number (slotted: a set holds thousands of them)."""

    question: str
    gold: float
    unit: str = ""
    category: str = ""
    profile: str = "plain"

    def __post_init__(self) -> None:
        if isinstance(self.gold, bool) or not isinstance(self.gold, (int, float)) or not math.isfinite(self.gold):
            raise ValueError(f"the gold value must be a finite number, got {self.gold!r:.60}")
        object.__setattr__(self, "gold", float(self.gold))
        if type(self.category) is str:
            object.__setattr__(self, "category", sys.intern(self.category))

    def shown(self, value: float) -> str:
        """``value`` with the question's unit (``"3.2 meters"``, ``"4"``)."""
        text = f"{value:g}"
        return f"{text} {self.unit}" if self.unit else text


def number_answer_schema() -> dict[str, object]:
    """JSON Schema of a numerical answer ``{"number"}``: what a strategy asking a number
    declares (``AnswerSpec.schema``), and what tells a parser reading both options and numbers
    which one it is asked."""
    return {"type": "object", "required": ["number"], "properties": {"number": {"type": "number"}}}


def asks_number(required_keys: tuple[str, ...]) -> bool:
    """Whether an answer spec with these required keys asks for a number."""
    return required_keys == ("number",)
