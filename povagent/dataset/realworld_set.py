"""Real-world evaluation sets: real frames, commands A/B/C, and a hand-marked ground truth.

The paper checks that the task's difficulty carries over to real houses: 30 frames from a
house-tour video, letterboxed to 512x512, a few observer-centric scenarios with commands in the
three conditions, and a manual success judgement per answer (unanswered counts as a failure).
This module is the format for such a set, its loader and writer, and the bridge that makes it
runnable by ``povagent run`` like any release-layout dataset.

A set is a folder holding ``realworld.json`` and the images it names (paths relative to it)::

    {
      "version": 1,
      "description": "two house tours",
      "houses": [
        {"id": "house_1",
         "frames": ["house_1/frame_00.jpg", ...],            # exploration frames (A/B), any size
         "scenarios": [
           {"id": "s1",
            "observer_view": "house_1/frame_07.jpg",          # the view for condition C
            "commands": [
              {"condition": "a", "direction": "right",
               "sentence": "While I was wiping the entrance ... on the right side of the table.",
               "gt": [{"frame": "house_1/frame_07.jpg", "point": [812, 455]},
                      {"frame": "house_1/frame_08.jpg", "box": [600, 380, 700, 460]}]},
              {"condition": "c", "direction": "right", "sentence": "The tissue box was ...",
               "gt": {"region": [[790, 430], [840, 430], [840, 480], [790, 480]]}}]}]}]}

Ground truth is marked in the *original* frame's pixels (continuous coordinates, see
:mod:`povagent.geometry.letterbox`), in one or more frames where the target would be (a command is a hit
when the selected frame carries a mark and the answer is within it). A mark is a ``point``
(a hit within a radius: the scorer's default, or the mark's own ``radius_px``), a ``box``
``[x0, y0, x1, y1]`` or a ``region`` polygon. A C command's marks are in the observer view and
may leave ``frame`` out.

Running it: :func:`load_realworld` returns a :class:`RealWorldDataset` with the loader's
interface (``houses``, ``instances(...)``, ``instance(id)``), whose instances show letterboxed
512x512 copies of the frames (written once to a cache folder) and carry the marks and the
letterbox transforms the ``success`` scorer needs. Instance ids are ``house/scenario/direction/
condition``. This module must not call models or score; the ``success`` scorer plugin scores.
"""

from __future__ import annotations

import io
import json
import os
import tempfile
import weakref
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from PIL import Image, UnidentifiedImageError
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from povagent.dataset.instances import Frame, Instance
from povagent.dataset.paths import dataset_root, is_inside
from povagent.dataset.problems import Problem, not_text_problems
from povagent.dataset.release_models import CONDITIONS, DIRECTIONS, AxisAlignedBoundingBox, Condition, Direction, RawMetadata, SceneObject, Vec3
from povagent.errors import ConfigError, DatasetError, ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, MAX_IMAGE_FILE_BYTES, read_regular
from povagent.geometry.camera import Camera
from povagent.geometry.letterbox import BENCHMARK_SIZE, Letterbox
from povagent.scoring.breakdown import slices

#: The file that makes a folder a real-world set.
INDEX_FILE = "realworld.json"
FORMAT_VERSION = 1

_CONDITION_NAMES = {"inferred": "a", "stated": "b", "given": "c"}


class _Strict(BaseModel):
    """Our own format: unknown keys are typos, reported rather than ignored."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class Mark(_Strict):
    """Where the target is in one frame: exactly one of ``point``, ``box`` or ``region``."""

    frame: str | None = None
    point: tuple[float, float] | None = None
    radius_px: float | None = Field(None, gt=0)
    box: tuple[float, float, float, float] | None = None
    region: list[tuple[float, float]] | None = None

    @model_validator(mode="after")
    def _one_shape(self) -> Mark:
        given = [k for k in ("point", "box", "region") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"a gt mark needs exactly one of point, box or region (got {', '.join(given) or 'none'})")
        if self.box is not None and not (self.box[0] < self.box[2] and self.box[1] < self.box[3]):
            raise ValueError(f"box must be [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got {list(self.box)}")
        if self.region is not None and len(self.region) < 3:
            raise ValueError("region must be a polygon of at least 3 [x, y] points")
        if self.radius_px is not None and self.point is None:
            raise ValueError("radius_px applies to point marks only")
        return self


class Command(_Strict):
    """One evaluation command: condition, direction, sentence and its ground-truth marks."""

    condition: Condition
    direction: Direction
    sentence: str = Field(min_length=1)
    gt: list[Mark] = Field(min_length=1)

    @field_validator("condition", mode="before")
    @classmethod
    def _condition_name(cls, value: Any) -> Any:
        return _CONDITION_NAMES.get(value.lower(), value.lower()) if isinstance(value, str) else value

    @field_validator("direction", mode="before")
    @classmethod
    def _direction_name(cls, value: Any) -> Any:
        return value.lower() if isinstance(value, str) else value

    @field_validator("gt", mode="before")
    @classmethod
    def _one_mark(cls, value: Any) -> Any:
        return [value] if isinstance(value, Mapping) else value


class Scenario(_Strict):
    """An observer-centric scenario: the observer view (for C) and its commands."""

    id: str = Field(min_length=1, pattern=r"^[^/#]+$")
    observer_view: str | None = None
    commands: list[Command] = Field(min_length=1)


class RealWorldHouse(_Strict):
    """One real house: its exploration frames (A/B) and scenarios."""

    id: str = Field(min_length=1, pattern=r"^[^/#]+$")
    frames: list[str] = Field(min_length=1)
    scenarios: list[Scenario] = Field(min_length=1)


class RealWorldSet(_Strict):
    """The whole ``realworld.json``."""

    version: int = FORMAT_VERSION
    description: str | None = None
    houses: list[RealWorldHouse] = Field(min_length=1)

    @field_validator("version")
    @classmethod
    def _known_version(cls, value: int) -> int:
        if value != FORMAT_VERSION:
            raise ValueError(f"unsupported realworld.json version {value} (this povagent reads version {FORMAT_VERSION})")
        return value


# -- reading and writing ---------------------------------------------------------------------------
def is_realworld(root: str | Path) -> bool:
    """True when ``root`` is a real-world set (holds ``realworld.json``)."""
    return (Path(root) / INDEX_FILE).is_file()


def read_realworld(root: str | Path) -> RealWorldSet:
    """Parse and check ``<root>/realworld.json``; :class:`DatasetError` names file and field.

    Checks beyond the schema: ids unique, every image exists and opens, every mark names a
    frame the command shows, C commands have an observer view, one command per
    (scenario, direction, condition).
    """
    root = Path(root)
    index = root / INDEX_FILE
    try:
        data = json.loads(read_regular(index, MAX_DOCUMENT_BYTES, what="real-world index").decode("utf-8"))
    except FileNotFoundError:
        raise DatasetError(f"{index}: not found (a real-world set is a folder holding {INDEX_FILE})") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{index}: cannot be read: {exc}") from None
    except json.JSONDecodeError as exc:
        raise DatasetError(f"{index}: not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}") from None
    not_text = not_text_problems(str(index), data)  # the same rule as a release's files
    if not_text:
        more = f" (and {len(not_text) - 1} more)" if len(not_text) > 1 else ""
        raise DatasetError(f"{not_text[0]}{more}")
    try:
        rw = RealWorldSet.model_validate(data)
    except ValidationError as exc:
        lines = []
        for e in exc.errors():
            where = _json_path(e["loc"])
            lines.append(f"{index}: {where}: {e['msg'].removeprefix('Value error, ')}")
        raise DatasetError("\n".join(lines)) from None
    _check_consistency(rw, root, index)
    return rw


def write_realworld(rw: RealWorldSet, root: str | Path) -> Path:
    """Write ``<root>/realworld.json`` (atomically); the images must already be in ``root``."""
    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    index = root / INDEX_FILE
    tmp = index.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(rw.model_dump(mode="json", exclude_none=True), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, index)
    return index


def _json_path(loc: Iterable[Any]) -> str:
    out = ""
    for p in loc:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _check_consistency(rw: RealWorldSet, root: Path, index: Path) -> None:
    problems: list[str] = []
    house_ids: set[str] = set()
    for hi, house in enumerate(rw.houses):
        hwhere = f"houses[{hi}] ({house.id})"
        if house.id in house_ids:
            problems.append(f"{hwhere}: house id {house.id!r} is used twice")
        house_ids.add(house.id)
        if len(set(house.frames)) != len(house.frames):
            problems.append(f"{hwhere}.frames: a frame is listed twice")
        for fi, rel in enumerate(house.frames):
            problems.extend(_image_problem(root, rel, f"{hwhere}.frames[{fi}]"))
        scenario_ids: set[str] = set()
        for si, sc in enumerate(house.scenarios):
            swhere = f"{hwhere}.scenarios[{si}] ({sc.id})"
            if sc.id in scenario_ids:
                problems.append(f"{swhere}: scenario id {sc.id!r} is used twice in house {house.id}")
            scenario_ids.add(sc.id)
            if sc.observer_view is not None:
                problems.extend(_image_problem(root, sc.observer_view, f"{swhere}.observer_view"))
            seen: set[tuple[str, str]] = set()
            for ci, cmd in enumerate(sc.commands):
                cwhere = f"{swhere}.commands[{ci}]"
                key = (cmd.direction.value, cmd.condition.value)
                if key in seen:
                    problems.append(f"{cwhere}: a second {cmd.direction.value}/{cmd.condition.value} command in this scenario")
                seen.add(key)
                if cmd.condition is Condition.GIVEN:
                    if sc.observer_view is None:
                        problems.append(f"{cwhere}: condition c needs the scenario's observer_view")
                        continue
                    shown = {sc.observer_view}
                else:
                    shown = set(house.frames)
                for mi, mark in enumerate(cmd.gt):
                    frame = mark.frame if mark.frame is not None else (sc.observer_view if cmd.condition is Condition.GIVEN else None)
                    if frame is None:
                        problems.append(f"{cwhere}.gt[{mi}].frame: required for condition {cmd.condition.value} (which frame is marked?)")
                    elif frame not in shown:
                        what = "the observer view" if cmd.condition is Condition.GIVEN else f"one of house {house.id}'s frames"
                        problems.append(f"{cwhere}.gt[{mi}].frame: {frame!r} is not {what}")
    if problems:
        raise DatasetError("\n".join(f"{index}: {p}" for p in problems))


def _image_problem(root: Path, rel: str, where: str) -> list[str]:
    path = root / rel
    if Path(rel).is_absolute() or ".." in Path(rel).parts:
        return [f"{where}: {rel!r} must be a path inside the set's folder"]
    if not is_inside(dataset_root(root), path):  # a symlink leading out: never opened
        return [f"{where}: {rel!r} leads outside the set's folder (a symlink); not opened"]
    try:
        with Image.open(io.BytesIO(read_regular(path, MAX_IMAGE_FILE_BYTES, what="image"))) as im:
            im.verify()
    except FileNotFoundError:
        return [f"{where}: image {rel} not found"]
    except ReadTargetError as exc:
        return [f"{where}: image {rel}: {exc.reason}; not read"]
    except (UnidentifiedImageError, OSError, SyntaxError) as exc:
        return [f"{where}: image {rel} cannot be read: {exc}"]
    return []


# -- running ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class RealWorldInstance(Instance):
    """An instance of a real-world set: frames letterboxed, GT as hand-made marks.

    ``marks`` are in original-frame pixels, each naming its frame's path (as in
    ``realworld.json``); ``letterboxes[i]`` maps ``frames[i]`` (the 512x512 square shown) back to
    the original. There is no 3D ground truth: ``target`` is NaN, and so are the observer and
    anchor objects (marker strategies draw nothing), so score with ``success``, not ``official``.
    """

    marks: tuple[Mark, ...] = ()
    letterboxes: tuple[Letterbox, ...] = ()
    original_sizes: tuple[tuple[int, int], ...] = ()

    def marks_in(self, image_path: str) -> list[Mark]:
        """The marks made in frame ``image_path``."""
        return [m for m in self.marks if m.frame == image_path]


@dataclass
class RealWorldDataset:
    """A loaded real-world set with the interface the runner uses (``houses``, ``instances``).

    ``problems`` is always empty (bad sets are refused whole, as they are small and hand-made).
    Letterboxed copies of the frames live in ``cache_dir`` (a temporary folder by default,
    removed when the dataset is collected).
    """

    root: Path
    spec: RealWorldSet
    cache_dir: Path
    houses: dict[str, RealWorldHouse]
    problems: list[Problem] = field(default_factory=list)
    _instances: list[RealWorldInstance] = field(default_factory=list, repr=False)
    _by_id: dict[str, RealWorldInstance] = field(default_factory=dict, repr=False)

    def instances(
        self,
        conditions: Iterable[Condition | str] | None = None,
        directions: Iterable[Direction | str] | None = None,
        houses: Iterable[str] | None = None,
    ) -> list[RealWorldInstance]:
        """Instances in file order (grouped by house), filtered like the release loader's."""
        cs = {Condition(c) for c in conditions} if conditions is not None else set(CONDITIONS)
        ds = {Direction(d) for d in directions} if directions is not None else set(DIRECTIONS)
        hs = set(houses) if houses is not None else None
        return [
            i for i in self._instances
            if i.condition in cs and i.direction in ds and (hs is None or i.house_id in hs)
        ]

    def instance(self, id_: str) -> RealWorldInstance | None:
        """The instance with id ``house/scenario/direction/condition``."""
        return self._by_id.get(id_)

    def check_scorers(self, scorers: Mapping[str, Any]) -> None:
        """Refuse scorers that need 3D ground truth (``Scorer.needs_3d_target``; the runner asks
        before any request).

        The marks are 2D: the ``official`` metric would project a NaN target, which its rules
        place at the image centre, and score a centre guess a perfect 0.
        """
        from povagent.scoring.score_protocols import registered_protocols

        needs_3d = sorted(name for name, scorer in scorers.items() if getattr(scorer, "needs_3d_target", False))
        if needs_3d:
            marked = [n for n, p in registered_protocols().items() if p == "marked_hit"]
            raise ConfigError(
                f"{self.root}: scorer {', '.join(needs_3d)} needs 3D ground truth, and a real-world set's is "
                f"marked by hand in 2D: use scorers: [{', '.join(marked)}]"
            )


def load_realworld(root: str | Path, cache_dir: str | Path | None = None) -> RealWorldDataset:
    """Read a real-world set and build its runnable instances (frames letterboxed once)."""
    root = Path(root)
    spec = read_realworld(root)
    own_tmp = cache_dir is None
    cache = Path(tempfile.mkdtemp(prefix="povagent-realworld-")) if cache_dir is None else Path(cache_dir)
    cache.mkdir(parents=True, exist_ok=True)
    squares: dict[str, tuple[Path, Letterbox]] = {}

    def square(rel: str) -> tuple[Path, Letterbox]:
        if rel not in squares:
            squares[rel] = _letterboxed_copy(root, rel, cache)
        return squares[rel]

    instances: list[RealWorldInstance] = []
    square_camera = unposed_square_camera()
    nowhere = unknown_object()
    for house in spec.houses:
        for sc in house.scenarios:
            for cmd in sc.commands:
                shown = [sc.observer_view] if cmd.condition is Condition.GIVEN else list(house.frames)
                frames, boxes = [], []
                for i, rel in enumerate(shown):
                    path, box = square(rel)  # type: ignore[arg-type]  # validation refuses a GIVEN command without an observer view
                    frames.append(Frame(i, rel, path, square_camera))  # type: ignore[arg-type]  # as above
                    boxes.append(box)
                marks = tuple(
                    m if m.frame is not None else m.model_copy(update={"frame": sc.observer_view}) for m in cmd.gt
                )
                instances.append(
                    RealWorldInstance(
                        house_id=house.id,
                        pair_id=sc.id,
                        direction=cmd.direction,
                        condition=cmd.condition,
                        sentence=cmd.sentence,
                        frames=tuple(frames),
                        target=(float("nan"),) * 3,
                        observer_object=nowhere,
                        anchor_object=nowhere,
                        observer_camera=square_camera,
                        marks=marks,
                        letterboxes=tuple(boxes),
                        original_sizes=tuple(b.original for b in boxes),
                    )
                )
    dataset = RealWorldDataset(root, spec, cache, {h.id: h for h in spec.houses}, [], instances,
                               {i.id: i for i in instances})
    if own_tmp:
        import shutil

        weakref.finalize(dataset, shutil.rmtree, str(cache), True)
    return dataset


def _letterboxed_copy(root: Path, rel: str, cache: Path) -> tuple[Path, Letterbox]:
    """The 512x512 letterboxed copy of ``root/rel`` in ``cache`` (made once), and its transform."""
    src = root / rel
    with Image.open(io.BytesIO(read_regular(src, MAX_IMAGE_FILE_BYTES, what="image"))) as im:
        im.load()
        box = Letterbox.for_size(*im.size)
        if box.is_identity and im.format == "PNG" and im.mode == "RGB":
            return src, box  # already a benchmark frame: shown as it is
        out = cache / (rel.replace("/", "__") + ".png")
        if not out.is_file() or out.stat().st_mtime < src.stat().st_mtime:
            tmp = out.with_suffix(".tmp.png")
            # compress_level fixed: the same source gives the same bytes, so cache keys hold
            box.apply(im).save(tmp, format="PNG", compress_level=6)
            os.replace(tmp, out)
    return out, box


def unknown_object(object_type: str = "Unknown") -> SceneObject:
    """An observer or anchor nobody measured: at NaN, so marker strategies draw nothing for it."""
    nan = float("nan")
    v = Vec3(x=nan, y=nan, z=nan)
    box = AxisAlignedBoundingBox(center=v, size=Vec3(x=0.0, y=0.0, z=0.0), cornerPoints=[[nan, nan, nan]] * 8)
    return SceneObject(objectId=f"unknown-{object_type}", position=v,
                       raw_metadata=RawMetadata(objectType=object_type, axisAlignedBoundingBox=box))


def unposed_square_camera() -> Camera:
    """The camera of a letterboxed frame whose pose is unknown: only its 512x512 size is real
    (strategies read the frame size from it; nothing may project through it)."""
    return Camera((0.0, 0.0, 0.0), 0.0, 0.0, 100.0, BENCHMARK_SIZE, BENCHMARK_SIZE)


# -- success summaries -----------------------------------------------------------------------------
def success_breakdown(rows: Iterable[Mapping[str, Any]]) -> dict[str, Any]:
    """Success rates as the paper reports them: successes / all instances (unanswered = failure).

    ``rows`` are dicts with ``condition``, ``direction`` and ``success`` (a bool; missing or
    ``None`` counts as a failure), and optionally ``answered`` (the success scorer's, or the
    report's reading of a row). Returns ``overall``, ``per_condition`` and ``per_direction``,
    each ``{n_total, n_success, success_rate}`` (and ``per_condition_direction``), plus ``{n_answered, response_rate}`` when the
    rows say whether they were answered.
    """
    rows = list(rows)
    with_answered = any("answered" in r for r in rows)

    def cell(sub: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
        hits = sum(1 for r in sub if r.get("success") is True)
        out = {"n_total": len(sub), "n_success": hits, "success_rate": hits / len(sub) if sub else None}
        if with_answered:
            answered = sum(1 for r in sub if r.get("answered") is True)
            out |= {"n_answered": answered, "response_rate": answered / len(sub) if sub else None}
        return out

    def label(key: str) -> Callable[[Mapping[str, Any]], str | None]:
        return lambda r: None if r.get(key) is None else str(r.get(key))

    return slices(rows, cell, condition=label("condition"), direction=label("direction"))


__all__ = [
    "Command",
    "INDEX_FILE",
    "Mark",
    "RealWorldDataset",
    "RealWorldHouse",
    "RealWorldInstance",
    "RealWorldSet",
    "Scenario",
    "is_realworld",
    "load_realworld",
    "read_realworld",
    "success_breakdown",
    "unknown_object",
    "unposed_square_camera",
    "write_realworld",
]
