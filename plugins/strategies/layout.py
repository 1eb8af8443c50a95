"""The paper's message layout, shared by the built-in strategies.

A/B: one user message holding, for each frame i, the text ``Image i:`` followed by the image,
then the prompt text ("The N images above ... Each image is preceded by its label"). C: the text
``Image:``, the observer view, then the prompt text (the authors' runner labels its one image
too). Also the :class:`AnswerSpec` each condition asks for.
Pure message assembly: no drawing, no model calls. Third-party strategies may reuse it.

Built once, shared after (all are immutable; a message is the same value either way): the image
parts of a frame set (the A/B instances of a house show the same frames), the labels of each
frame count, and the :class:`AnswerSpec` of each (condition kind, frame count, frame size).
The answer spec's ``json_schema`` dict is therefore shared: read it, never change it.
"""

from __future__ import annotations

import threading
from functools import lru_cache
from typing import Sequence

from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema
from povagent.dataset.instances import Frame, Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Part, TextPart


def frame_label(index: int) -> str:
    """The text label shown before frame ``index``: ``Image 0:``, ``Image 1:`` ..."""
    return f"Image {index}:"


def shown_images(instance: Instance, images: ImageStore, frames: Sequence[Frame] | None = None) -> list[str]:
    """Hashes of ``frames`` (default: all the instance's), added to the run's image store (each
    file read once)."""
    return [images.add_file(frame.file).image_hash for frame in (instance.frames if frames is None else frames)]


@lru_cache(maxsize=64)
def _frame_labels(n: int) -> tuple[tuple[TextPart, str], ...]:
    """For each of ``n`` frames: the label part shown before it and the image part's label."""
    return tuple((TextPart(frame_label(i)), f"Image {i}") for i in range(n))


#: The text part the authors' runner sends before the observer view (C).
GIVEN_LABEL = "Image:"

#: Image parts by (labelled?, C label, image hashes): the A/B instances of a house share their frames.
_IMAGE_PARTS_MAX = 256
_image_parts: dict[tuple[bool, str | None, tuple[str, ...]], tuple[Part, ...]] = {}
_image_parts_lock = threading.Lock()


def image_parts(image_hashes: Sequence[str], labelled: bool, given_label: str | None = GIVEN_LABEL) -> tuple[Part, ...]:
    """The parts showing ``image_hashes``: each preceded by its ``Image i:`` label when
    ``labelled`` (A/B), else as ``observer view`` images (C), preceded by the text part
    ``given_label`` unless it is ``None``. Built once per frame set."""
    key = (labelled, None if labelled else given_label, tuple(image_hashes))
    parts = _image_parts.get(key)
    if parts is not None:
        return parts
    if labelled:
        built: list[Part] = []
        for (label_part, label), image_hash in zip(_frame_labels(len(key[2])), key[2]):
            built.append(label_part)
            built.append(ImagePart(image_hash, label=label))
        parts = tuple(built)
    else:
        views = tuple(ImagePart(h, label="observer view") for h in key[2])
        parts = views if given_label is None else (TextPart(given_label), *views)
    with _image_parts_lock:
        if len(_image_parts) >= _IMAGE_PARTS_MAX:
            _image_parts.clear()  # a frame set per house: a run goes through them in order
        _image_parts[key] = parts
    return parts


def prompt_message(
    instance: Instance, image_hashes: Sequence[str], prompt_text: str, given_label: str | None = GIVEN_LABEL
) -> Message:
    """The user message: labelled frames (A/B) or the labelled observer view (C), then the prompt text."""
    parts = image_parts(image_hashes, instance.povbench_condition.uses_exploration_frames, given_label)
    return Message("user", (*parts, TextPart(prompt_text)))


@lru_cache(maxsize=256, typed=True)  # typed: a float size must not reuse an int size's schema
def _answer_spec(asks_frame: bool, n_frames: int, width: int, height: int) -> AnswerSpec:
    if asks_frame:
        schema = frame_answer_schema(n_frames, width, height)
    else:
        schema = point_answer_schema(width, height)
    return AnswerSpec(schema=schema, width=width, height=height, n_frames=n_frames, asks_frame=asks_frame)


def answer_spec(instance: Instance, n_frames: int | None = None) -> AnswerSpec:
    """What the paper's prompts ask for: ``{selected_image, x, y}`` (A/B) or ``{x, y}`` (C).

    ``n_frames`` is the number of frames shown (default: all of the instance's). One shared
    (frozen) spec per condition kind, frame count and frame size.
    """
    width, height = instance.frame_size
    if instance.povbench_condition.uses_exploration_frames:
        return _answer_spec(True, len(instance.frames) if n_frames is None else n_frames, width, height)
    return _answer_spec(False, 1, width, height)
