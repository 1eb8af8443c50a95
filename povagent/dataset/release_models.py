"""Pydantic models of the POVBench release layout.

Strict where a mistake would silently corrupt scores (an unknown direction, a camera without a
position, a bounding box without its corner points); tolerant where the real release varies
(sentences as strings or as objects holding ``sentence``, ids as numbers or strings, and extra
keys anywhere, which are kept and ignored). No number read from a release file may be NaN or
infinite, extra keys included (validate with ``context=RELEASE_FILE``): Python's ``json`` reads
them, and a NaN position silently corrupts the ground truth. Records built in code may hold NaN
on purpose (a real-world set's unmeasured objects). The JSON Schemas shipped in ``povagent/schemas`` are
generated from these models (``python -m povagent.dataset.schema``).
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationInfo, WithJsonSchema, field_validator, model_validator
from pydantic_core import PydanticCustomError

from povagent.dataset.problems import non_finite_numbers
from povagent.geometry.directions import DIRECTION_REGISTRY

#: The spatial relations of POVBench, one member per entry of the directions registry
#: (:mod:`povagent.geometry.directions`, which holds each one's words and rules), in its order.
Direction = StrEnum("Direction", {spec.name.upper(): spec.name for spec in DIRECTION_REGISTRY}, module=__name__)  # type: ignore[misc]
Direction.__doc__ = "The spatial relations of POVBench, in the order of the directions registry."


class Condition(StrEnum):
    """How explicitly the sentence grounds the observer (the paper's A, B and C)."""

    INFERRED = "a"
    STATED = "b"
    GIVEN = "c"

    @property
    def label(self) -> str:
        """The paper's name: Inferred, Stated or Given."""
        return {"a": "Inferred", "b": "Stated", "c": "Given"}[self.value]

    @property
    def uses_exploration_frames(self) -> bool:
        """A and B show the exploration frames; C shows the one observer view."""
        return self is not Condition.GIVEN


#: The largest image side a camera may declare (POVBench renders 512x512).
MAX_SCREEN_SIDE = 16384
#: The largest side (m) an object's box may have: a house is tens of metres across, and the
#: per-instance geometry (the relation region's samples) is sized by the anchor's box.
MAX_OBJECT_SIDE_M = 100.0

DIRECTIONS: tuple[Direction, ...] = tuple(Direction)
CONDITIONS: tuple[Condition, ...] = (Condition.INFERRED, Condition.STATED, Condition.GIVEN)


def _as_sentence(value: Any) -> Any:
    """The release stores a sentence as a string or as ``{"sentence": ..., ...}``."""
    if isinstance(value, dict) and "sentence" in value:
        return value["sentence"]
    return value


def _as_str_id(value: Any) -> Any:
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return str(value)
    return value


Sentence = Annotated[
    str,
    BeforeValidator(_as_sentence),
    Field(min_length=1),
    WithJsonSchema(
        {
            "anyOf": [
                {"type": "string", "minLength": 1},
                {
                    "type": "object",
                    "required": ["sentence"],
                    "properties": {"sentence": {"type": "string", "minLength": 1}},
                },
            ]
        }
    ),
]
Identifier = Annotated[
    str,
    BeforeValidator(_as_str_id),
    Field(min_length=1),
    WithJsonSchema({"anyOf": [{"type": "string", "minLength": 1}, {"type": "integer"}]}),
]
Float3 = Annotated[list[float], Field(min_length=3, max_length=3)]


#: Validation context for data read from a release file: every number must be finite.
RELEASE_FILE: dict[str, Any] = {"release_file": True}


class _Record(BaseModel):
    """Base of every release record: extra keys are kept and ignored, never rejected."""

    model_config = ConfigDict(extra="allow", populate_by_name=True)

    @model_validator(mode="after")
    def _finite_in_release_files(self, info: ValidationInfo) -> _Record:
        # Each record checks its own numbers (fields, lists of them, extra keys); nested records
        # check theirs, so the reported path is exact.
        if isinstance(info.context, dict) and info.context.get("release_file"):
            own = {**self.__dict__, **(self.model_extra or {})}
            for loc, value in non_finite_numbers(own):
                raise PydanticCustomError("non_finite", "not a finite number", {"at": list(loc), "value": value})
        return self


class Vec3(_Record):
    """A 3D point ``{x, y, z}`` in metres (Unity world: y up)."""

    x: float
    y: float
    z: float

    def as_tuple(self) -> tuple[float, float, float]:
        """``(x, y, z)``."""
        return (self.x, self.y, self.z)


ObjectSide = Annotated[float, Field(ge=-MAX_OBJECT_SIDE_M, le=MAX_OBJECT_SIDE_M)]


class BoxSize(Vec3):
    """A box's side lengths (m), each at most :data:`MAX_OBJECT_SIDE_M` in magnitude."""

    x: ObjectSide
    y: ObjectSide
    z: ObjectSide


class AxisAlignedBoundingBox(_Record):
    """An object's world-space box as AI2-THOR reports it."""

    center: Vec3
    # a plain Vec3 built in code (a real-world set's unmeasured box) is checked as a size too
    size: Annotated[BoxSize, BeforeValidator(lambda v: v.model_dump() if type(v) is Vec3 else v)]
    cornerPoints: Annotated[list[Float3], Field(min_length=8, max_length=8)]



class RawMetadata(_Record):
    """The part of AI2-THOR's object metadata the benchmark keeps."""

    objectType: str = Field(min_length=1)
    position: Vec3 | None = None
    axisAlignedBoundingBox: AxisAlignedBoundingBox


class SceneObject(_Record):
    """An observer or anchor (landmark) object."""

    objectId: Identifier
    assetId: str | None = None
    position: Vec3
    raw_metadata: RawMetadata

    @property
    def object_type(self) -> str:
        """The AI2-THOR objectType (e.g. ``Bed``)."""
        return self.raw_metadata.objectType


class ObserverCamera(_Record):
    """The observer camera of a pair: the view rendered for condition C."""

    cam_pos: Float3
    cam_yaw: float
    cam_horizon: float
    fov: float = Field(default=100.0, gt=0, lt=180)
    screen_width: int = Field(default=512, gt=0, le=MAX_SCREEN_SIDE)
    screen_height: int = Field(default=512, gt=0, le=MAX_SCREEN_SIDE)


class SurfaceJudgement(_Record):
    """Stage 3: is a target plausible in this direction, and on which surface."""

    verdict: str
    surface: str | None = None


class InferredStatedSentences(_Record):
    """Stage 5: the A (Inferred) and B (Stated) sentences of one direction."""

    type_a: Sentence
    type_b: Sentence


class GivenSentence(_Record):
    """Stage 6: the C (Given) sentence of one direction."""

    type_c: Sentence


class Placement(_Record):
    """The raw 3D target point of one direction."""

    position: Vec3


class PairEntry(_Record):
    """One (observer, anchor) pair of a house file, with its valid directions."""

    pair_id: Identifier
    landmark_type: str = Field(min_length=1)
    object_landmark: SceneObject
    object_observer: SceneObject
    camera: ObserverCamera
    rgb_path: str = Field(min_length=1)
    stage3: dict[Direction, SurfaceJudgement] = Field(default_factory=dict)
    stage5: dict[Direction, InferredStatedSentences]
    stage6: dict[Direction, GivenSentence]
    placements: dict[Direction, Placement]

    @field_validator("placements")
    @classmethod
    def _at_least_one_direction(cls, v: dict[Direction, Placement]) -> dict[Direction, Placement]:
        if not v:
            raise ValueError("a pair needs at least one direction in placements")
        return v

    def valid_directions(self) -> list[Direction]:
        """Directions with a placement, in the canonical order right, left, front, up."""
        return [d for d in DIRECTIONS if d in self.placements]


class ExplorationCamera(_Record):
    """The pose of one exploration frame (no size: frames take the dataset's frame size)."""

    cam_pos: Float3
    cam_yaw: float
    cam_horizon: float
    fov: float = Field(default=100.0, gt=0, lt=180)


class ExplorationRecord(_Record):
    """One exploration frame: where it is, how it was taken, what it shows."""

    image_path: str = Field(min_length=1)
    camera: ExplorationCamera
    object_in_frame_hits: list[Identifier] = Field(default_factory=list)


class DatasetMeta(_Record):
    """``meta.json``: free-form metadata. The release does not document it; every field is optional."""

    version: str | None = None
    seed: int | None = None
