"""A gallery card of a multiple-choice row: the question, its images, every option, the option
chosen and the gold option, beside the reply.

A choice row has no point and often no frame it selected (ViewSpatial-Bench, MindCube and
3DSRBench questions, povagent's ``task: relation`` in every condition), so its card shows the
question's own images: the first as the card's image, all of them as a strip when there are
several (a question's frames, or a house's exploration frames in conditions A and B). The
chosen label is what the run's choice scorer recorded (:attr:`Observation.chosen`), the gold
and the options are the question's (:class:`~povagent.answers.choice_question.ChoiceQuestion`).

This module only says what a card shows; drawing and naming the files is
:mod:`povagent.report.gallery`'s job, and nothing here scores.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from povagent.report.collect import Observation
from povagent.report.gallery_drawing import Drawing

#: A card's ``gt_state`` for a question image: nothing is marked on it.
QUESTION_IMAGE = "question"


def asked_question(instance: Any) -> Any:
    """The multiple-choice question an instance asks (``None``: it asks for no choice)."""
    return getattr(instance, "question", None) if instance is not None else None


def asks_numeric_question(instance: Any) -> bool:
    """Whether the instance asks a numerical question (VSI-Bench's: a card like a choice
    question's, its images and no options)."""
    return getattr(instance, "numeric", None) is not None if instance is not None else False


def shows_several_images(instance: Any) -> bool:
    """Whether the instance asks a question shown with several images (they get a strip)."""
    asks = asked_question(instance) is not None or asks_numeric_question(instance)
    return asks and len(getattr(instance, "frames", ())) > 1


def has_target(instance: Any) -> bool:
    """Whether the instance has a 3D target a frame may show (an external set's has none: NaN)."""
    return all(math.isfinite(v) for v in instance.target)


def question_drawing(instance: Any) -> Drawing | None:
    """The card's image of a question: its first image, unmarked (``None``: it shows none)."""
    frames = getattr(instance, "frames", ())
    return Drawing(Path(frames[0].file), None, QUESTION_IMAGE, None) if frames else None


def choice_fields(o: Observation, question: Any) -> dict[str, Any]:
    """An entry's choice fields: ``qo`` the options ``[[label, text], ...]``, ``qg`` the gold
    label, ``qc`` the label chosen (``None``: the reply named no option) and ``qk`` whether it
    is the gold one."""
    return {
        "qo": [[label, text] for label, text in question.options],
        "qg": question.gold,
        "qc": o.chosen,
        "qk": o.chosen is not None and o.chosen == question.gold,
    }
