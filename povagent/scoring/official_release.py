"""A release read the way the official scorer reads it, for counting exactly as it counts.

``evaluation/eval_results.py`` (mimo-owl/povbench-eval) indexes a release loosely where
povagent's loader (:mod:`povagent.dataset.loader`) checks it: pairs are keyed by ``(house_id,
pair_id)`` with the id as the file writes it (``7`` and ``"7"`` are different pairs), an
exploration log by its records' ``image_path`` exactly as written (``./exploration_images/x.png``
names nothing a prediction writes), no image file is looked at, and a pair is scored whatever
its other fields hold: an empty ``landmark_type`` (no anchor keyword then matters), an anchor box
without ``center`` (the anchor's ``position`` stands in, else the origin), without
``cornerPoints`` (the top is the centre's height), missing camera fields (position at the
origin, yaw and horizon 0, fov 100, the metadata's screen size).

:func:`read_release` builds that index; :meth:`OfficialRelease.target` is the ground truth the
official scorer computes from it (through the same placement rules,
:func:`povagent.geometry.ground_truth.target_point`). What stays povagent's own, on purpose:
no file outside the dataset folder is opened (a symlinked house file or a ``house_id`` such as
``../x`` names nothing), and a value the official code would stop on (a house file that is not
JSON, a coordinate that is text) is reported in a warning and counted rather than stopping the
whole evaluation.

Reading files only; the arithmetic is the geometry's and the metric's.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from povagent.dataset.paths import dataset_root, is_inside
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular
from povagent.geometry.camera import Camera
from povagent.geometry.ground_truth import AnchorBox, target_point
from povagent.scoring.normalized_l2 import GroundTruthInFrame, project_ground_truth

#: The official scorer's defaults for a camera field a record lacks.
DEFAULT_FOV = 100.0
DEFAULT_CAM_POS = (0.0, 0.0, 0.0)
#: A missing ``camera`` object, read as officially (``{}``: every field at its default).
NO_CAMERA: Mapping[str, Any] = MappingProxyType({})


class NotScorable(ValueError):
    """A value the official scorer would stop on (it has no way to go on): the row is counted
    unanswered and named in a warning instead."""


def _mapping(value: Any, what: str) -> Mapping[str, Any]:
    """``value`` if it is an object; the official code calls ``.get`` on it and stops otherwise."""
    if not isinstance(value, Mapping):
        raise NotScorable(f"{what} is not an object")
    return value


def _number(value: Any, what: str) -> float:
    """A coordinate as the official code converts it (``float()``); anything else stops it."""
    if isinstance(value, str) or value is None:
        raise NotScorable(f"{what} is not a number")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise NotScorable(f"{what} is not a number") from None


def point_of(value: Any, what: str) -> tuple[float, float, float]:
    """A 3D point written as ``{x, y, z}`` or ``[x, y, z]``, as the official projection reads it."""
    if isinstance(value, Mapping):
        try:
            return tuple(_number(value[k], f"{what}.{k}") for k in "xyz")  # type: ignore[return-value]
        except KeyError as exc:
            raise NotScorable(f"{what} has no {exc.args[0]}") from None
    if isinstance(value, (list, tuple)) and len(value) >= 3:
        return (_number(value[0], what), _number(value[1], what), _number(value[2], what))
    raise NotScorable(f"{what} is not a 3D point")


@dataclass(frozen=True)
class CameraRecord:
    """A camera as the official scorer reads one: each missing field at its default."""

    position: tuple[float, float, float]
    yaw: float
    horizon: float
    fov: float
    width: float | None
    height: float | None

    @classmethod
    def read(cls, raw: Any, what: str) -> CameraRecord:
        """From a ``camera`` object (``{}`` when absent, as officially)."""
        cam = _mapping(raw, what)
        pos = cam.get("cam_pos", list(DEFAULT_CAM_POS))
        width, height = cam.get("screen_width"), cam.get("screen_height")
        return cls(
            point_of(pos, f"{what}.cam_pos"),
            _number(cam.get("cam_yaw", 0.0), f"{what}.cam_yaw"),
            _number(cam.get("cam_horizon", 0.0), f"{what}.cam_horizon"),
            _number(cam.get("fov", DEFAULT_FOV), f"{what}.fov"),
            None if width is None else _number(width, f"{what}.screen_width"),
            None if height is None else _number(height, f"{what}.screen_height"),
        )


def anchor_box_as_released(landmark: Any) -> AnchorBox:
    """The anchor's box as the official scorer reads it from ``object_landmark``: the box
    centre, else the object's ``position``, else the origin; half of ``size`` (0 when absent);
    the highest corner, else the centre's height."""
    lm = _mapping(landmark, "object_landmark")
    raw = _mapping(lm.get("raw_metadata", {}), "object_landmark.raw_metadata")
    box = _mapping(raw.get("axisAlignedBoundingBox", {}), "axisAlignedBoundingBox")
    centre = _mapping(box.get("center") or lm.get("position") or {}, "axisAlignedBoundingBox.center")
    size = _mapping(box.get("size", {}), "axisAlignedBoundingBox.size")
    corners = box.get("cornerPoints", [])
    cx, cy, cz = (_number(centre.get(k, 0), f"center.{k}") for k in "xyz")
    hx, hz = _number(size.get("x", 0), "size.x") / 2, _number(size.get("z", 0), "size.z") / 2
    try:
        top = max(_number(c[1], "cornerPoints") for c in corners) if corners else cy
    except (TypeError, IndexError, KeyError):
        raise NotScorable("cornerPoints are not points") from None
    return AnchorBox((cx, cz), (hx, hz), top)


@dataclass
class OfficialRelease:
    """A release indexed as the official scorer indexes it (see the module docstring)."""

    root: Path
    #: Pair entries by ``(house_id, pair_id as written)``; a repeated key: the last entry.
    pairs: dict[tuple[str, Any], Mapping[str, Any]]
    #: What could not be read, for the score's warnings.
    warnings: list[str] = field(default_factory=list)
    _logs: dict[str, dict[str, Mapping[str, Any]]] = field(default_factory=dict, repr=False)
    #: Each (entry, direction)'s ground truth, computed once: a run names the same instance in
    #: thousands of rows. Keyed by identity and kept beside the objects it was computed from.
    _targets: dict[tuple[int, int, Any, str], tuple[Any, Any, tuple[float, float, float]]] = field(default_factory=dict, repr=False)
    _cameras: dict[int, tuple[Any, CameraRecord]] = field(default_factory=dict, repr=False)
    _projections: dict[tuple[tuple[float, float, float], int, float, float], tuple[CameraRecord, GroundTruthInFrame]] = field(
        default_factory=dict, repr=False
    )

    def entry(self, house_id: Any, pair_id: Any) -> Mapping[str, Any] | None:
        """The pair entry a prediction names, or ``None`` (ids compared as written)."""
        try:
            return self.pairs.get((house_id, pair_id))
        except TypeError:  # an unhashable id names nothing
            return None

    def log(self, house_id: str) -> dict[str, Mapping[str, Any]]:
        """A house's exploration records by ``image_path`` as written (the last of a repeated
        path); ``{}`` when the house has no log (or names a folder outside the dataset)."""
        if house_id not in self._logs:
            self._logs[house_id] = self._read_log(house_id)
        return self._logs[house_id]

    def _read_log(self, house_id: str) -> dict[str, Mapping[str, Any]]:
        artifacts = self.root / "artifacts"
        path = artifacts / house_id / "exploration_log.json"
        if "/" in house_id or "\\" in house_id or house_id in ("", ".", "..") or not path.is_file():
            return {}
        if not is_inside(dataset_root(self.root), path):
            self.warnings.append(f"{path}: leads outside the dataset folder; not opened (no frame of {house_id} is known)")
            return {}
        try:
            records = json.loads(read_regular(path, MAX_DOCUMENT_BYTES, what="exploration log").decode("utf-8"))
        except (OSError, ReadTargetError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
            self.warnings.append(f"{path}: unreadable ({exc}); no frame of {house_id} is known (the official scorer stops here)")
            return {}
        if not isinstance(records, list):
            self.warnings.append(f"{path}: not a list of records; no frame of {house_id} is known (the official scorer stops here)")
            return {}
        return {r["image_path"]: r for r in records if isinstance(r, Mapping) and "image_path" in r and _hashable(r["image_path"])}

    def target(self, entry: Mapping[str, Any], direction: Any, raw_position: Any) -> tuple[float, float, float]:
        """The 3D ground truth of one (pair, direction), as the official scorer computes it: the
        surface-corrected point when ``stage3`` judges the direction appropriate, else the raw
        placement ``raw_position``. Computed once per (entry, direction, position)."""
        # the key holds the direction as a key and as text (1 and True find the same stage3 entry
        # but name different rules); the value holds the objects, so their ids stay theirs
        if not _hashable(direction):
            return self._target(entry, direction, raw_position)
        key = (id(entry), id(raw_position), direction, str(direction))
        cached = self._targets.get(key)
        if cached is not None and cached[0] is entry and cached[1] is raw_position:
            return cached[2]
        point = self._target(entry, direction, raw_position)
        self._targets[key] = (entry, raw_position, point)
        return point

    def camera(self, raw: Any, what: str) -> CameraRecord:
        """:meth:`CameraRecord.read` of one of the release's camera objects, read once per
        object (rows name the same few frames and observer cameras again and again)."""
        cached = self._cameras.get(id(raw))
        if cached is not None and cached[0] is raw:
            return cached[1]
        record = CameraRecord.read(raw, what)
        self._cameras[id(raw)] = (raw, record)
        return record

    def ground_truth_in(self, target: tuple[float, float, float], camera: CameraRecord, width: float, height: float) -> GroundTruthInFrame:
        """:func:`project_ground_truth` of a target in a camera record (as :meth:`camera` read
        it) at ``width`` x ``height``, projected once per target, record and size."""
        key = (target, id(camera), width, height)
        cached = self._projections.get(key)
        if cached is not None and cached[0] is camera:
            return cached[1]
        # a size read as written divides as officially (a float as well as an int)
        gt = project_ground_truth(target, Camera(camera.position, camera.yaw, camera.horizon, camera.fov, width, height))  # type: ignore[arg-type]
        self._projections[key] = (camera, gt)
        return gt

    def _target(self, entry: Mapping[str, Any], direction: Any, raw_position: Any) -> tuple[float, float, float]:
        raw = point_of(raw_position, "placement.position")
        stage3 = _mapping(entry.get("stage3", {}), "stage3")
        info = stage3.get(direction) if _hashable(direction) else None
        if not info or _mapping(info, f"stage3.{direction}").get("verdict") != "appropriate":
            return raw
        surface = str(info.get("surface") or "").lower()
        anchor_type = entry.get("landmark_type", "")
        landmark = entry.get("object_landmark", {})
        box = anchor_box_as_released(landmark)
        lm_pos = _mapping(_mapping(landmark, "object_landmark").get("position", {}), "object_landmark.position")
        anchor_xz = np.array([_number(lm_pos.get("x", 0), "position.x"), 0.0, _number(lm_pos.get("z", 0), "position.z")])
        observer = np.array(CameraRecord.read(entry.get("camera", {}), "camera").position)
        point = target_point(
            str(direction),
            box,
            anchor_type if isinstance(anchor_type, str) else "",
            anchor_xz,
            observer,
            "appropriate",
            surface,
            np.array(raw),
        )
        return (float(point[0]), float(point[1]), float(point[2]))


def _hashable(value: Any) -> bool:
    try:
        hash(value)
    except TypeError:
        return False
    return True


def house_files(root: Path) -> list[Path]:
    """The pair files the official scorer reads: ``train_house_*.json`` at the root, else
    ``artifacts/*/train_house_*.json``, sorted."""
    files = sorted(root.glob("train_house_*.json"))
    return files or sorted((root / "artifacts").glob("*/train_house_*.json"))


def read_release(root: str | Path) -> OfficialRelease:
    """Index a release's pairs as the official scorer does (its exploration logs are read when
    a prediction names a house). A file that cannot be read is named in a warning and its pairs
    are unknown; an entry that is not an object stops the file's reading there, as officially."""
    root = Path(root)
    release = OfficialRelease(root, {})
    real = dataset_root(root)
    for path in house_files(root):
        if not is_inside(real, path):
            release.warnings.append(f"{path}: leads outside the dataset folder; not opened")
            continue
        try:
            entries = json.loads(read_regular(path, MAX_DOCUMENT_BYTES, what="house file").decode("utf-8"))
        except (OSError, ReadTargetError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
            release.warnings.append(f"{path.name}: unreadable ({exc}); its pairs are unknown, as officially")
            continue
        for i, entry in enumerate(entries if isinstance(entries, list) else []):
            if not isinstance(entry, Mapping):
                release.warnings.append(f"{path.name}: entry {i} is not an object; the rest of the file is skipped, as officially")
                break
            pair_id = entry.get("pair_id", "")
            if not _hashable(pair_id):
                release.warnings.append(f"{path.name}: entry {i}'s pair_id is a list or object; the rest of the file is skipped, as officially")
                break
            release.pairs[(path.stem, pair_id)] = entry
    return release
