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

from dataclasses import dataclass


@dataclass(frozen=True)
class ChoiceQuestion:
    """One question with labelled options (``(("A", "left"), ("B", "right"))``) and the gold label."""

    question: str
    options: tuple[tuple[str, str], ...]
    gold: str
    category: str = ""
    group: str = ""
    variant: str = ""
    profile: str = "plain"
    main_category: str = ""

    def __post_init__(self) -> None:
        labels = self.labels
        if len(set(labels)) != len(labels):
            raise ValueError(f"option labels repeat: {', '.join(labels)}")
        if self.gold not in labels:
            raise ValueError(f"the gold label {self.gold!r} is not among the options ({', '.join(labels)})")

    @property
    def labels(self) -> tuple[str, ...]:
        """The option labels, in the order shown."""
        return tuple(label for label, _ in self.options)

    def text_of(self, label: str) -> str | None:
        """The text of option ``label`` (``None``: no such option)."""
        return next((text for lab, text in self.options if lab == label), None)

    def options_block(self) -> str:
        """The options one per line, ``A. left``."""
        return "\n".join(f"{label}. {text}" for label, text in self.options)
