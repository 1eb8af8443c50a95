"""The paper's message layout, shared by the built-in strategies.

A/B: one user message holding, for each frame i, the text ``Image i:`` followed by the image,
then the prompt text ("The N images above ... Each image is preceded by its label"). C: the
observer view, then the prompt text. Also the :class:`AnswerSpec` each condition asks for.
Pure message assembly: no drawing, no model calls. Third-party strategies may reuse it.
"""

from __future__ import annotations

from typing import Sequence

from povagent.answers import AnswerSpec, frame_answer_schema, point_answer_schema
from povagent.dataset.instances import Instance
from povagent.exchange import ImagePart, Message, Part, TextPart
from povagent.images import ImageStore


def frame_label(index: int) -> str:
    """The text label shown before frame ``index``: ``Image 0:``, ``Image 1:`` ..."""
    return f"Image {index}:"


def shown_images(instance: Instance, images: ImageStore) -> list[str]:
    """Hashes of the instance's frames, added to the run's image store (each file read once)."""
    return [images.add_file(frame.file).image_hash for frame in instance.frames]


def prompt_message(instance: Instance, image_hashes: Sequence[str], prompt_text: str) -> Message:
    """The user message: labelled frames (A/B) or the observer view (C), then the prompt text."""
    parts: list[Part] = []
    if instance.condition.uses_exploration_frames:
        for i, image_hash in enumerate(image_hashes):
            parts.append(TextPart(frame_label(i)))
            parts.append(ImagePart(image_hash, label=f"Image {i}"))
    else:
        parts.extend(ImagePart(h, label="observer view") for h in image_hashes)
    parts.append(TextPart(prompt_text))
    return Message("user", tuple(parts))


def answer_spec(instance: Instance) -> AnswerSpec:
    """What the paper's prompts ask for: ``{selected_image, x, y}`` (A/B) or ``{x, y}`` (C)."""
    width, height = instance.frame_size
    if instance.condition.uses_exploration_frames:
        n = len(instance.frames)
        return AnswerSpec(
            schema=frame_answer_schema(n, width, height), width=width, height=height, n_frames=n, asks_frame=True
        )
    return AnswerSpec(schema=point_answer_schema(width, height), width=width, height=height, n_frames=1, asks_frame=False)
