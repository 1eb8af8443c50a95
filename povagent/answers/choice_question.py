"""A multiple-choice question: the question as asked, its labelled options and the gold label.

What an instance carries when it asks for a ``choice`` answer (``Instance.question``): the
perspective-taking sets' questions (ViewSpatial-Bench, MindCube, 3DSRBench) and the relation
tasks povagent generates on its own houses. ``category`` is the set's question type (the slice
accuracy is broken down by), ``main_category`` the broader type it belongs to where the set has
one (3DSRBench's ``orientation`` for ``orientation_viewpoint``: a slice too); ``group`` and ``variant`` tie together the records a set scores
jointly (3DSRBench's circular and flipped copies of one question). ``profile`` names the prompt
wording the set is asked in (:mod:`povagent_plugins.strategies.choice`).

Pure values: nothing here reads files or parses answers.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

#: Option tuples met so far, each kept once: a set's questions repeat a few option lists (the
#: directions, shuffled), so 10,000 questions share a few dozen tuples instead of holding 10,000.
#: Each with its labels as a set when no label repeats (``None``: they repeat), so a question
#: sharing it checks its gold label without listing them again. Bounded: past it, new option
#: lists are kept by their own question only.
_SHARED_OPTIONS: dict[tuple[tuple[str, str], ...], tuple[tuple[tuple[str, str], ...], frozenset[str] | None]] = {}
_MAX_SHARED_OPTIONS = 4096


@dataclass(frozen=True, slots=True)
class ChoiceQuestion:
    """One question with labelled options (``(("A", "left"), ("B", "right"))``) and the gold label
    (slotted: a set of 10,000 questions holds 10,000 of them)."""

    question: str
    options: tuple[tuple[str, str], ...]
    gold: str
    category: str = ""
    group: str = ""
    variant: str = ""
    profile: str = "plain"
    main_category: str = ""

    def __post_init__(self) -> None:
        shared = None
        if type(self.options) is tuple:
            try:  # a list already kept (most questions' options): no need to check its types again
                shared = _SHARED_OPTIONS.get(self.options)
            except TypeError:  # an option that cannot be hashed (not a tuple of texts): kept as given
                shared = None
            if (
                shared is None
                and len(_SHARED_OPTIONS) < _MAX_SHARED_OPTIONS
                and all(type(o) is tuple and len(o) == 2 and type(o[0]) is str and type(o[1]) is str for o in self.options)
            ):
                kept = tuple((sys.intern(label), sys.intern(text)) for label, text in self.options)
                names = [label for label, _ in kept]
                shared = _SHARED_OPTIONS.setdefault(self.options, (kept, frozenset(names) if len(set(names)) == len(names) else None))
            if shared is not None:
                object.__setattr__(self, "options", shared[0])  # equal values: the question is the same
        if type(self.category) is str:
            object.__setattr__(self, "category", sys.intern(self.category))
        if shared is not None and shared[1] is not None and type(self.gold) is str:  # labels known not to repeat
            if self.gold not in shared[1]:
                raise ValueError(f"the gold label {self.gold!r} is not among the options ({', '.join(self.labels)})")
            return
        labels = self.labels
        if len(set(labels)) != len(labels):
            raise ValueError(f"option labels repeat: {', '.join(labels)}")
        if self.gold not in labels:
            raise ValueError(f"the gold label {self.gold!r} is not among the options ({', '.join(labels)})")

    @property
    def labels(self) -> tuple[str, ...]:
        """The option labels, in the order shown."""
        return tuple([label for label, _ in self.options])  # a list first: faster than a generator

    def options_block(self) -> str:
        """The options one per line, ``A. left``."""
        return "\n".join(f"{label}. {text}" for label, text in self.options)
