"""One training example per (instance, condition): the benchmark's request, then the answer.

The question is exactly what the benchmark sends for the instance: the strategy plugin that
matches the rationale (``none`` -> ``basic``, ``cot`` -> ``cot``, ``s-cot`` -> ``spatial-cot``)
builds its request, so the labels, the prompt text and the image order are the benchmark's own.
The answer is the rationale text from :mod:`povagent.train.rationale`, ending in the JSON line.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from povagent.dataset.instances import Instance
from povagent.dataset.loader import House
from povagent.errors import DatasetError, ReadTargetError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, TextPart
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular
from povagent.tasks.scene_facts import InstanceFacts, NoTeachingFrame, PixelBox, instance_facts
from povagent.train.choice_rationale import choice_rationale_text
from povagent.train.rationale import rationale_text

if TYPE_CHECKING:  # the generator's scene loads only when a task asks
    from povagent.tasks.multi_hop import Hop

#: The strategy whose prompt asks for each kind of rationale.
STRATEGY_FOR_RATIONALE = {"none": "basic", "cot": "cot", "s-cot": "spatial-cot"}


@dataclass(frozen=True)
class QuestionPart:
    """A part of the user turn: ``text``, or an image given by its path inside the house folder."""

    text: str | None = None
    image: str | None = None


@dataclass(frozen=True)
class ExampleImage:
    """An image of a question: the file it was read from, its label, and what it held.

    ``label`` is the image's path under the dataset's ``artifacts/`` folder
    (``house/exploration_images/x.png``), only ever written as a value inside a row; an export
    names its own files after ``sha256`` (never after the dataset's text), and writes the bytes
    only while they still hash to it.
    """

    file: Path
    label: str
    sha256: str
    media_type: str


@dataclass(frozen=True)
class TrainingExample:
    """A question (parts in the benchmark's order), the answer text, and where it came from."""

    id: str
    house_id: str
    pair_id: str
    direction: str
    condition: str
    parts: tuple[QuestionPart, ...]
    images: tuple[ExampleImage, ...]
    answer: str
    answer_json: str
    facts: InstanceFacts

    @property
    def image_files(self) -> tuple[Path, ...]:
        """The images' files, in the order the question shows them."""
        return tuple(i.file for i in self.images)

    @property
    def question_text(self) -> str:
        """The prompt text of the question (the text parts after the last image)."""
        texts: list[str] = []
        for part in self.parts:
            if part.image is not None:
                texts = []
            elif part.text is not None:
                texts.append(part.text)
        return "\n".join(texts)

    def identity(self, split: str) -> dict[str, str]:
        """The fields naming the example, first in every format's row."""
        return {
            "id": self.id,
            "house_id": self.house_id,
            "pair_id": self.pair_id,
            "direction": self.direction,
            "condition": self.condition,
            "split": split,
        }

    def facts_record(self) -> dict[str, Any]:
        """The stated facts as plain JSON values (kept in every row, for checking and filtering)."""
        f = self.facts

        def box(b: PixelBox | None) -> list[int] | None:
            return None if b is None else [b.x0, b.y0, b.x1, b.y1]

        return {
            "frame_index": f.frame_index,
            "frame_path": f.frame_path,
            "observer_visible": f.observer_visible,
            "anchor_visible": f.anchor_visible,
            "anchor_xy": [round(v, 3) for v in f.anchor_xy],
            "anchor_box": box(f.anchor_box),
            "anchor_other_views": [
                {"frame_index": v.frame_index, "xy": [round(c, 3) for c in v.xy], "box": box(v.box)} for v in f.anchor_other_views
            ],
            "observer_xy": None if f.observer_xy is None else [round(v, 3) for v in f.observer_xy],
            "speaker_offset": [round(v, 3) for v in f.speaker_offset],
            "facing_deg": round(f.facing_deg, 2),
            "facing": f.facing,
            "relation": f.relation,
            "image_direction": f.image_direction,
            "surface": f.surface,
            "answer_xy": list(f.answer_xy),
        }


def image_bytes(image: ExampleImage) -> bytes:
    """``image``'s bytes, read again from its file for writing; a file that changed since the
    question was built (another size, other bytes) is a :class:`DatasetError` naming it, never
    a different image written under the old one's name."""
    try:
        data = read_regular(image.file, MAX_IMAGE_FILE_BYTES, what="image")
    except ReadTargetError as exc:
        raise DatasetError(str(exc)) from None
    except OSError as exc:
        raise DatasetError(f"{image.file}: cannot be read again for the export ({exc.strerror or exc})") from None
    if hashlib.sha256(data).hexdigest() != image.sha256:
        raise DatasetError(f"{image.file}: changed since export-train read it (other bytes now); run the export again")
    return data


def image_label(house: House, source: Path) -> str:
    """``source``'s path under the dataset's ``artifacts/`` folder, spelled without ``..``.

    An observer view may be named relative to the dataset root and live in another house's
    folder (or outside ``artifacts/``): the label then says where it is, or is its file name
    alone; it is a value in a row, never a path anything is written to.
    """
    artifacts = Path(os.path.normpath(house.folder.parent))
    where = Path(os.path.normpath(source))
    return where.relative_to(artifacts).as_posix() if where.is_relative_to(artifacts) else where.name


#: The strategy that asks a generated task's multiple-choice question (whatever the rationale).
CHOICE_STRATEGY = "choice"


def make_strategy(rationale: str, task: str = "point") -> Any:
    """The built-in strategy whose prompt fits ``rationale`` (a generated task's: the one asking
    its question), made through the plugin host."""
    from povagent.plugins import get_plugin_host

    name = STRATEGY_FOR_RATIONALE[rationale] if task == "point" else CHOICE_STRATEGY
    return get_plugin_host().strategy(name, {})


def house_examples(
    house: House,
    instances: list[Instance],
    rationale: str,
    strategy: Any,
    seed: int,
    exact: bool = False,
    hop_of: Callable[[str], Hop | None] | None = None,
) -> Iterator[TrainingExample | tuple[str, str]]:
    """Each instance of ``house`` as an example; ``(instance id, reason)`` for one that cannot teach.

    ``strategy`` is :func:`make_strategy`'s; a fresh image store per house keeps memory flat.
    An instance asking a multiple-choice question is answered with its label
    (:mod:`povagent.train.choice_rationale`; ``hop_of`` names a multi-hop instance's intermediate).
    """
    images = ImageStore()
    for inst in instances:
        pair = house.pairs[inst.pair_id]
        try:
            facts = instance_facts(inst, pair)
        except NoTeachingFrame as exc:
            yield (inst.id, str(exc).partition(": ")[2])
            continue
        request = strategy.build(inst, images)
        parts: list[QuestionPart] = []
        shown: list[ExampleImage] = []
        for message in request.messages:
            for part in message.parts:
                if isinstance(part, TextPart):
                    parts.append(QuestionPart(text=part.text))
                elif isinstance(part, ImagePart):
                    source = images.source_file(part.image_hash)
                    if source is None:  # a drawn image: the built-in text strategies draw none
                        raise ValueError(f"{inst.id}: strategy {strategy!r} sent an image that is not a dataset file")
                    image = ExampleImage(source, image_label(house, source), part.image_hash, images.info(part.image_hash).media_type)
                    parts.append(QuestionPart(image=image.label))
                    shown.append(image)
        if inst.question is not None:
            answer = choice_rationale_text(facts, inst.question, rationale, hop_of(inst.id) if hop_of else None)
        else:
            answer = rationale_text(facts, rationale, seed=seed, exact=exact)
        yield TrainingExample(
            id=inst.id,
            house_id=inst.house_id,
            pair_id=inst.pair_id,
            direction=inst.povbench_direction.value,
            condition=inst.povbench_condition.value,
            parts=tuple(parts),
            images=tuple(shown),
            answer=answer,
            answer_json=answer.rsplit("\n", 1)[-1],
            facts=facts,
        )
