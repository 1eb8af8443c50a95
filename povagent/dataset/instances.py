"""Evaluation instances: one per (pair, valid direction, condition).

An instance knows everything a strategy, a backend and a scorer need and nothing about files
beyond the frame paths: the sentence, the frames it shows (A/B: the exploration frames in the
official order, every PNG of ``exploration_images/`` sorted by file name, depth maps left out;
C: the observer view), the ground-truth 3D point, and the observer and anchor objects
(for visual markers).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from povagent.answers.choice_question import ChoiceQuestion
from povagent.answers.numeric_question import NumericQuestion
from povagent.dataset.release_models import Condition, Direction, SceneObject
from povagent.geometry.camera import Camera


@dataclass(frozen=True)
class Frame:
    """An image an instance shows, with the camera it was taken from.

    ``image_path`` is the key predictions use to name a frame (relative to the house folder);
    ``file`` is where it is on disk; ``in_frame_hits`` the objectIds the renderer saw in it
    (the exploration log's ``object_in_frame_hits``; empty for an observer view).
    """

    index: int
    image_path: str
    file: Path
    camera: Camera
    in_frame_hits: frozenset[str] = frozenset()


@dataclass(frozen=True)
class Instance:
    """One evaluation instance; ``id`` is ``house/pair/direction/condition`` (an external
    multiple-choice set's item, with no direction or condition: ``set/record``)."""

    house_id: str
    pair_id: str
    #: POVBench's direction and condition; ``None`` for an item of an external multiple-choice
    #: set (:mod:`povagent.dataset.choice_sets`), which has neither.
    direction: Direction | None
    condition: Condition | None
    sentence: str
    frames: tuple[Frame, ...]
    target: tuple[float, float, float]
    observer_object: SceneObject
    anchor_object: SceneObject
    observer_camera: Camera
    #: The multiple-choice question the instance asks (:mod:`povagent.answers.choice_question`), or
    #: ``None`` for POVBench's point task.
    question: ChoiceQuestion | None = None
    #: The answer type the instance asks for (a registered ``AnswerType``'s name): a strategy
    #: asking another is refused at load (:func:`povagent.answers.types.answer_type_misfit`).
    #: An instance carrying a :attr:`question` asks for a ``choice`` unless it names another type.
    answer_type: str = "point"
    #: The question the instance asks when it asks for a number (:mod:`povagent.answers.numeric_question`:
    #: VSI-Bench's numerical-answer questions), or ``None``. Such an instance asks for a
    #: ``number`` unless it names another type.
    numeric: NumericQuestion | None = None

    def __post_init__(self) -> None:
        if self.question is not None and self.answer_type == "point":
            object.__setattr__(self, "answer_type", "choice")
        elif self.numeric is not None and self.answer_type == "point":
            object.__setattr__(self, "answer_type", "number")

    @property
    def id(self) -> str:
        """Stable id ``house/pair/direction/condition``."""
        return instance_id(self.house_id, self.pair_id, self.direction, self.condition)

    @property
    def answers_a_frame(self) -> bool:
        """Whether an answer names one of several frames (POVBench's A/B: the exploration
        frames); false for C and for an external item, whose answer names no frame."""
        return self.condition is not None and self.condition.uses_exploration_frames

    @property
    def povbench_condition(self) -> Condition:
        """The condition, for code that only POVBench's point task runs (a point strategy, the
        official scorer); an external multiple-choice item has none and is refused here."""
        if self.condition is None:
            raise ValueError(
                f"instance {self.id} is a multiple-choice item with no POVBench condition: ask it with the choice strategy and score it with a choice scorer"
            )
        return self.condition

    @property
    def povbench_direction(self) -> Direction:
        """The direction, for code that only POVBench's point task runs; refused as
        :attr:`povbench_condition` is for an external item."""
        if self.direction is None:
            raise ValueError(
                f"instance {self.id} is a multiple-choice item with no POVBench direction: ask it with the choice strategy and score it with a choice scorer"
            )
        return self.direction

    @property
    def frame_size(self) -> tuple[int, int]:
        """``(width, height)`` of the frames shown (all frames of an instance share it)."""
        cam = self.frames[0].camera if self.frames else self.observer_camera
        return (cam.width, cam.height)

    def selected_frame(self, selected_image: int | None) -> Frame | None:
        """The frame an answer's ``selected_image`` names, or ``None`` when it names none.

        The one rule for a valid frame index: ``0 <= k < len(frames)``. A negative index is
        invalid (never Python's "from the end"), as is ``None``; the official scorer leaves such
        a row unanswered.
        """
        if selected_image is None or not 0 <= selected_image < len(self.frames):
            return None
        return self.frames[selected_image]

    def frame_by_path(self, image_path: str) -> Frame | None:
        """The shown frame whose ``image_path`` matches (also tolerating a leading ``./``); when
        the exploration log repeats a path, the last record wins, as officially."""
        want = image_path.removeprefix("./")
        for f in reversed(self.frames):
            if f.image_path.removeprefix("./") == want:
                return f
        return None


def instance_id(house_id: str, pair_id: str, direction: str | None, condition: str | None) -> str:
    """``house/pair/direction/condition`` with enum values as plain strings; an external set's
    item (no direction, no condition) is ``set/record``."""
    if direction is None or condition is None:
        return f"{house_id}/{pair_id}"
    return f"{house_id}/{pair_id}/{direction!s}/{condition!s}"


def row_key(instance_id_: str, run: int) -> str:
    """The key of one (instance, run): ``<instance id>#<run>``."""
    return f"{instance_id_}#{run}"
