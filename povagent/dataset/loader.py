"""Loading a dataset in the POVBench release layout into typed houses and instances.

Loading never crashes on one bad house or pair: it records a :class:`Problem` and goes on
(``strict=True`` raises instead). A dataset is untrusted: no file outside the dataset folder is
ever opened (a house naming one is refused), no number may be NaN or infinite, no string may
hold what is not text (:mod:`povagent.dataset.json_files`), and every image
a run would send is checked once here (complete, of its camera's size) rather than failing
mid-run. Thorough checks of every file are the job of :mod:`povagent.dataset.validate`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any, Iterable, Mapping, cast

import numpy as np
from pydantic import TypeAdapter, ValidationError

from povagent.dataset.image_files import image_problem
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.json_files import read_dataset_json
from povagent.dataset.paths import OutsideDatasetError, confined, dataset_root, observer_view_path
from povagent.dataset.problems import Problem, folder_name_problem, problems_from_validation_error
from povagent.dataset.release_models import (
    CONDITIONS,
    RELEASE_FILE,
    Condition,
    DatasetMeta,
    Direction,
    ExplorationRecord,
    PairEntry,
)
from povagent.errors import DatasetError
from povagent.geometry.camera import Camera
from povagent.geometry.ground_truth import AnchorBox, PlacementCase

_VISIBLE = TypeAdapter(dict[str, list[str]])

EXPLORATION_LOG = "exploration_log.json"
VISIBLE_OBJECTS = "per_image_visible_objects.json"


@dataclass
class House:
    """One house: its pairs, exploration frames and per-frame visible objects."""

    house_id: str
    folder: Path
    pairs: dict[str, PairEntry]
    exploration: list[ExplorationRecord]
    visible_objects: dict[str, list[str]]
    frame_size: tuple[int, int] = (512, 512)
    #: The exploration frames' paths in the official order (``None``: the log's, by that rule).
    frame_paths: tuple[str, ...] | None = None

    @cached_property
    def frames(self) -> tuple[Frame, ...]:
        """Exploration frames in the official order (:func:`official_frame_paths`), shared by
        every A/B instance of the house; each takes its camera and hits from its log record
        (the last record of a path, when the log repeats one)."""
        w, h = self.frame_size
        records = log_records(self.exploration)
        paths = self.frame_paths if self.frame_paths is not None else official_frame_paths(None, self.exploration)
        frames = []
        for i, path in enumerate(p for p in paths if p in records):
            rec = records[path]
            frames.append(
                Frame(
                    index=i,
                    image_path=path,
                    file=self.folder / path,
                    camera=Camera.from_pose(rec.camera.cam_pos, rec.camera.cam_yaw, rec.camera.cam_horizon, rec.camera.fov, w, h),
                    in_frame_hits=frozenset(rec.object_in_frame_hits),
                )
            )
        return tuple(frames)

    @cached_property
    def frames_by_path(self) -> dict[str, Frame]:
        """Exploration frames by ``image_path``; when a path repeats in the log, the last record
        wins, as in the official scorer (``povagent validate`` reports the repeat)."""
        return {f.image_path: f for f in self.frames}

    def observer_frame(self, pair: PairEntry) -> Frame:
        """The observer view of a pair (condition C)."""
        return Frame(0, pair.rgb_path, resolve_image(self.folder, pair.rgb_path, self._real_places), observer_camera(pair))

    @cached_property
    def _real_places(self) -> tuple[Path, Path]:
        """The dataset's real root and this house's real folder, resolved once for its observer
        views (each condition-C instance asks for one)."""
        return dataset_root(self.folder.parent.parent), self.folder.resolve()


#: The folder of a house's exploration frames; a file whose name contains ``depth`` is a depth map.
EXPLORATION_IMAGES = "exploration_images"
DEPTH_MARK = "depth"


def log_records(exploration: list[ExplorationRecord]) -> dict[str, ExplorationRecord]:
    """Log records by image path (a leading ``./`` dropped); a repeated path: the last record wins."""
    return {rec.image_path.removeprefix("./"): rec for rec in exploration}


def official_frame_paths(house_folder: Path | None, exploration: list[ExplorationRecord]) -> tuple[str, ...]:
    """The frames the official runner shows, in its order: every ``*.png`` in
    ``exploration_images/`` whose name does not contain ``depth``, sorted by file name, as
    ``exploration_images/<name>``. Frame ``k`` of a prediction is the k-th of this list.

    When the folder holds no such file (or ``house_folder`` is ``None``), the log's image paths
    under the same rule (a dataset shipped without its frames can still be scored)."""
    folder = house_folder / EXPLORATION_IMAGES if house_folder is not None else None
    if folder is not None and folder.is_dir():
        names = sorted(p.name for p in folder.glob("*.png") if DEPTH_MARK not in p.name)
        if names:
            return tuple(f"{EXPLORATION_IMAGES}/{name}" for name in names)
    paths = {rec.image_path.removeprefix("./") for rec in exploration}
    return tuple(sorted(p for p in paths if p.endswith(".png") and DEPTH_MARK not in Path(p).name))


def observer_camera(pair: PairEntry) -> Camera:
    """The observer camera of a pair."""
    c = pair.camera
    return Camera.from_pose(c.cam_pos, c.cam_yaw, c.cam_horizon, c.fov, c.screen_width, c.screen_height)


def resolve_image(house_folder: Path, rel: str, real_places: tuple[Path, Path] | None = None) -> Path:
    """An image path of the release, relative to the house folder (or, failing that, the root);
    a path leading outside the dataset is a :class:`DatasetError` (loading refuses such houses).
    ``real_places``: the dataset's real root and the house's real folder, when known."""
    real_root, real_folder = real_places if real_places is not None else (dataset_root(house_folder.parent.parent), None)
    try:
        return observer_view_path(real_root, house_folder, rel, real_folder)
    except OutsideDatasetError as exc:
        raise DatasetError(f"{house_folder / rel}: {exc}") from None


def anchor_box(pair: PairEntry) -> AnchorBox:
    """The anchor's AABB as the GT rules use it."""
    box = pair.object_landmark.raw_metadata.axisAlignedBoundingBox
    top = max(c[1] for c in box.cornerPoints)
    return AnchorBox((box.center.x, box.center.z), (box.size.x / 2.0, box.size.z / 2.0), top)


def anchor_type(pair: PairEntry) -> str:
    """The anchor's type for the surface rules: the pair's ``landmark_type``, as the official
    scorer reads it, with no fallback there. The ``raw_metadata.objectType`` stand-in for an
    empty one is povagent's own: the loader refuses a pair without ``landmark_type``, and
    ``povagent score`` (official counting) scores such a pair with the empty type, as officially."""
    return pair.landmark_type or pair.object_landmark.object_type


def placement_case(pair: PairEntry, direction: Direction | str) -> PlacementCase:
    """What the placement rules read for one (pair, direction), as the official scorer reads it."""
    # Direction is a str enum: the plain name finds the same entry
    key = cast(Direction, direction)
    judgement = pair.stage3.get(key)
    box = pair.object_landmark.raw_metadata.axisAlignedBoundingBox
    return PlacementCase(
        direction=str(direction),
        box=anchor_box(pair),
        anchor_type=anchor_type(pair),
        anchor_position=pair.object_landmark.position.as_tuple(),
        anchor_centre=box.center.as_tuple(),
        observer_position=tuple(float(v) for v in pair.camera.cam_pos),  # type: ignore[arg-type]
        verdict=judgement.verdict if judgement else None,
        surface=judgement.surface if judgement else None,
        raw_placement=pair.placements[key].position.as_tuple(),
    )


def ground_truth_point(pair: PairEntry, direction: Direction | str) -> np.ndarray:
    """The surface-corrected 3D GT point of one (pair, direction), as the official scorer has it."""
    return placement_case(pair, direction).target()


@dataclass
class Dataset:
    """A loaded dataset: houses by id, plus the problems met while loading."""

    root: Path
    meta: DatasetMeta | None
    houses: dict[str, House]
    problems: list[Problem] = field(default_factory=list)
    # Instances are immutable: each is built once (GT point, observer view) and reused by every
    # selection (a sweep selects from one loaded dataset once per cell).
    _built: dict[tuple[str, str, Direction, Condition], Instance] = field(default_factory=dict, init=False, repr=False)
    # The GT point of each (house, pair, direction), computed once: scoring names the same
    # instance in thousands of rows.
    _targets: dict[tuple[str, str, str, str], tuple[float, float, float]] = field(default_factory=dict, init=False, repr=False)

    def target(self, house_id: str, pair: PairEntry, direction: Direction | str) -> tuple[float, float, float]:
        """The 3D GT point of ``pair`` (of house ``house_id``) in ``direction``
        (:func:`ground_truth_point`), computed once per dataset."""
        key = (house_id, pair.pair_id, direction, str(direction))
        point = self._targets.get(key)
        if point is None:
            gx, gy, gz = (float(v) for v in ground_truth_point(pair, direction))
            point = self._targets[key] = (gx, gy, gz)
        return point

    def instances(
        self,
        conditions: Iterable[Condition | str] | None = None,
        directions: Iterable[Direction | str] | None = None,
        houses: Iterable[str] | None = None,
    ) -> list[Instance]:
        """Every instance, grouped by house (so a run reads each house's frames together)."""
        conds = [Condition(c) for c in conditions] if conditions else list(CONDITIONS)
        dirs = {Direction(d) for d in directions} if directions else None
        keep = set(houses) if houses else None
        out: list[Instance] = []
        built = self._built
        for house in self.houses.values():
            if keep is not None and house.house_id not in keep:
                continue
            for pair in house.pairs.values():
                obs_cam = None
                for direction in pair.valid_directions():
                    if dirs is not None and direction not in dirs:
                        continue
                    target = None
                    for cond in conds:
                        key = (house.house_id, pair.pair_id, direction, cond)
                        inst = built.get(key)
                        if inst is None:
                            if target is None:
                                obs_cam = obs_cam or observer_camera(pair)
                                target = tuple(float(v) for v in ground_truth_point(pair, direction))
                            inst = built[key] = self._instance(house, pair, direction, cond, target, obs_cam)
                        out.append(inst)
        return out

    def _instance(self, house: House, pair: PairEntry, direction: Direction, cond: Condition, target, obs_cam) -> Instance:
        if cond is Condition.GIVEN:
            sentence = pair.stage6[direction].type_c
            frames: tuple[Frame, ...] = (house.observer_frame(pair),)
        else:
            s5 = pair.stage5[direction]
            sentence = s5.type_a if cond is Condition.INFERRED else s5.type_b
            frames = house.frames
        return Instance(
            house_id=house.house_id,
            pair_id=pair.pair_id,
            direction=direction,
            condition=cond,
            sentence=sentence,
            frames=frames,
            target=target,
            observer_object=pair.object_observer,
            anchor_object=pair.object_landmark,
            observer_camera=obs_cam,
        )

    @cached_property
    def _index(self) -> dict[str, Instance]:
        return {i.id: i for i in self.instances()}

    def instance(self, id_: str) -> Instance | None:
        """The instance with id ``house/pair/direction/condition``, or ``None``."""
        return self._index.get(id_)

    def check_scorers(self, scorers: Mapping[str, Any]) -> None:
        """Every scorer can score a release-layout set (its ground truth is 3D): no-op."""


def _read_json(path: Path, root: Path, problems: list[Problem]) -> Any:
    return read_dataset_json(path, _rel(path, root), dataset_root(root), problems)


def _rel(path: Path, root: Path) -> str:
    try:
        return str(path.relative_to(root))
    except ValueError:
        return str(path)


def house_folders(root: Path) -> list[Path]:
    """House folders under ``root/artifacts`` in sorted order."""
    art = root / "artifacts"
    if not art.is_dir():
        return []
    return sorted(p for p in art.iterdir() if p.is_dir())


def load_house(
    folder: Path, root: Path, problems: list[Problem], frame_size: tuple[int, int] = (512, 512), check_images: bool = True
) -> House | None:
    """Load one house; bad pairs are reported and skipped, an unusable house returns ``None``.

    ``check_images=False`` skips the image checks (not the rule that every file stays inside
    the dataset): for readers that only draw, and say so on a bad image themselves.
    """
    house_id = folder.name
    not_text = folder_name_problem(_rel(folder, root))
    if not_text is not None:
        problems.append(not_text)
        return None
    before = len(problems)
    raw_pairs = _read_json(folder / f"{house_id}.json", root, problems)
    raw_log = _read_json(folder / EXPLORATION_LOG, root, problems)
    if raw_pairs is None or raw_log is None:
        return None
    pairs_file = _rel(folder / f"{house_id}.json", root)
    log_file = _rel(folder / EXPLORATION_LOG, root)
    if not isinstance(raw_pairs, list):
        problems.append(Problem(pairs_file, "$", f"must be a list of pair entries (got {type(raw_pairs).__name__})"))
        return None
    if not isinstance(raw_log, list):
        problems.append(Problem(log_file, "$", f"must be a list of frame records (got {type(raw_log).__name__})"))
        return None
    pairs: dict[str, PairEntry] = {}
    for i, raw in enumerate(raw_pairs):
        try:
            pair = PairEntry.model_validate(raw, context=RELEASE_FILE)
        except ValidationError as exc:
            problems.extend(problems_from_validation_error(pairs_file, exc, (i,)))
            continue
        missing = [d for d in pair.valid_directions() if d not in pair.stage5 or d not in pair.stage6]
        if missing:
            names = ", ".join(str(d) for d in missing)
            problems.append(Problem(pairs_file, f"$[{i}]", f"direction(s) {names} have a placement but no sentence in stage5/stage6"))
            continue
        if pair.pair_id in pairs:
            # the official scorer indexes pairs by id, so the later entry replaces the earlier
            problems.append(
                Problem(pairs_file, f"$[{i}].pair_id", f"pair_id {pair.pair_id!r} appears twice in this house; the last entry is used, as officially")
            )
            del pairs[pair.pair_id]  # keep file order for the replacing entry
        pairs[pair.pair_id] = pair
    exploration: list[ExplorationRecord] = []
    log_ok = True
    for i, raw in enumerate(raw_log):
        try:
            exploration.append(ExplorationRecord.model_validate(raw, context=RELEASE_FILE))
        except ValidationError as exc:
            problems.extend(problems_from_validation_error(log_file, exc, (i,)))
            log_ok = False
    if not log_ok:
        # A/B frame indices would shift if a record were dropped: the house cannot be scored.
        return None
    visible: dict[str, list[str]] = {}
    vis_path = folder / VISIBLE_OBJECTS
    if vis_path.exists():
        raw_vis = _read_json(vis_path, root, problems)
        if raw_vis is not None:
            try:
                visible = _VISIBLE.validate_python(raw_vis, context=RELEASE_FILE)
            except ValidationError as exc:
                problems.extend(problems_from_validation_error(_rel(vis_path, root), exc))
    if not pairs and len(problems) > before:
        return None
    frame_paths = official_frame_paths(folder, exploration)
    # every file the house names must stay inside the dataset: checked before anything else
    # about its frames, so an escape is reported as such
    sound = _with_sound_files(
        House(house_id, folder, pairs, exploration, visible, frame_size, frame_paths), raw_pairs, raw_log, root, problems, check_images
    )
    if sound is None:
        return None
    unlogged = [p for p in frame_paths if p not in log_records(exploration)]
    if unlogged:
        # the official runner shows these frames too: without their cameras the house's frame
        # indices and scores cannot be reproduced
        shown = ", ".join(unlogged[:5]) + (" ..." if len(unlogged) > 5 else "")
        problems.append(Problem(log_file, "$", f"no record for {len(unlogged)} frame(s) of {EXPLORATION_IMAGES}/: {shown}"))
        return None
    return sound


def _with_sound_files(
    house: House, raw_pairs: list[Any], raw_log: list[Any], root: Path, problems: list[Problem], check_images: bool
) -> House | None:
    """``house`` if every file it names stays inside the dataset and its frames are sound
    images; pairs with a bad observer view are dropped. Each problem names file and field.

    A path leading out of the dataset refuses the whole house (its files are untrusted); a bad
    exploration frame too (dropping it would shift the A/B frame indices predictions use).
    """
    real_root = dataset_root(root)
    real_folder = house.folder.resolve()  # every frame's path is checked against it: resolved once
    log_file = _rel(house.folder / EXPLORATION_LOG, root)
    pairs_file = _rel(house.folder / f"{house.house_id}.json", root)
    usable = True
    # frames not shipped at all (a Given-only download has no exploration_images/) are not
    # checked: the house still serves its Given instances
    shipped = (house.folder / EXPLORATION_IMAGES).is_dir()
    shown = set(house.frame_paths or ()) if shipped else set()
    for i, rec in enumerate(house.exploration):
        where = f"$[{_raw_index(raw_log, 'image_path', rec.image_path, i)}].image_path"
        try:
            path = confined(real_root, house.folder, rec.image_path, real_base=real_folder)
        except OutsideDatasetError as exc:
            problems.append(Problem(log_file, where, str(exc)))
            usable = False
            continue
        # only frames that are shown are images to check: a record whose file is not on disk is
        # never shown (the official frame list is the folder's PNGs), so it is no problem
        problem = image_problem(path, rec.image_path, house.frame_size) if check_images and rec.image_path in shown else None
        if problem is not None:
            problems.append(Problem(log_file, where, problem))
            usable = False
    for pair_id, pair in list(house.pairs.items()):
        where = f"$[{_raw_index(raw_pairs, 'pair_id', pair_id, -1)}].rgb_path"
        try:
            path = observer_view_path(real_root, house.folder, pair.rgb_path, real_folder)
        except OutsideDatasetError as exc:
            problems.append(Problem(pairs_file, where, str(exc)))
            usable = False
            continue
        size = (pair.camera.screen_width, pair.camera.screen_height)
        # observer views not shipped at all (an A/B-only download) are not checked: the pair
        # still serves its Inferred and Stated instances
        views_shipped = path.parent.is_dir()
        problem = image_problem(path, pair.rgb_path, size) if check_images and views_shipped else None
        if problem is not None:
            problems.append(Problem(pairs_file, where, problem + "; the pair is skipped"))
            del house.pairs[pair_id]
    return house if usable and house.pairs else None


def _raw_index(raw: list[Any], key: str, value: str, default: int) -> int:
    """The index of the raw entry a loaded record came from: ``default`` when that entry's
    ``key`` is ``value``, else the last such entry (ids compare as strings, as the models read
    them; a repeated pair id keeps its last entry)."""
    if 0 <= default < len(raw) and isinstance(raw[default], dict) and str(raw[default].get(key)) == value:
        return default
    for i in range(len(raw) - 1, -1, -1):
        entry = raw[i]
        if isinstance(entry, dict) and str(entry.get(key)) == value:
            return i
    return default


def dataset_house_folders(root: Path) -> list[Path]:
    """:func:`house_folders` of a dataset folder, or :class:`DatasetError` saying what is missing."""
    if not root.is_dir():
        raise DatasetError(f"{root}: dataset folder not found (expected the POVBench release layout: meta.json, artifacts/<house>/...)")
    folders = house_folders(root)
    if not folders:
        raise DatasetError(f"{root}: no house folders under {root / 'artifacts'} (is this a POVBench dataset?)")
    return folders


def read_meta(root: Path, problems: list[Problem]) -> DatasetMeta | None:
    """The dataset's ``meta.json`` (``None`` when there is none, or it is unusable: then the
    problems say why)."""
    if not (root / "meta.json").exists():
        return None
    raw_meta = _read_json(root / "meta.json", root, problems)
    if raw_meta is None:
        return None
    try:
        return DatasetMeta.model_validate(raw_meta, context=RELEASE_FILE)
    except ValidationError as exc:
        problems.extend(problems_from_validation_error("meta.json", exc))
        return None


def load_dataset(
    root: str | Path, *, strict: bool = False, frame_size: tuple[int, int] = (512, 512), check_images: bool = True
) -> Dataset:
    """Load a dataset folder in the release layout.

    Problems (a malformed house file, a bad pair, a path leading outside the dataset, a
    truncated or wrongly sized image) are collected in ``Dataset.problems`` and the affected
    house or pair is skipped. With ``strict=True`` any problem raises :class:`DatasetError`
    listing them all. ``check_images=False`` skips the image checks (each image is read once
    per process for them); paths are always kept inside the dataset.
    """
    root = Path(root)
    folders = dataset_house_folders(root)
    problems: list[Problem] = []
    meta = read_meta(root, problems)
    houses: dict[str, House] = {}
    for folder in folders:
        house = load_house(folder, root, problems, frame_size, check_images)
        if house is not None:
            houses[house.house_id] = house
    if strict and problems:
        listing = "\n".join(f"  - {p}" for p in problems)
        raise DatasetError(f"{root}: {len(problems)} problem(s) found (loading is --strict):\n{listing}")
    if not houses:
        listing = "\n".join(f"  - {p}" for p in problems[:20])
        raise DatasetError(f"{root}: no usable house; problems:\n{listing}")
    return Dataset(root, meta, houses, problems)
