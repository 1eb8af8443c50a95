"""Scoring predictions against a dataset: official rows or our own results rows, already read.

``povagent score`` and the reports use this; finding and reading the files is
:mod:`povagent.results.prediction_files`' job, so this room stays pure. Official rows (see
POVBENCH.md, read by :func:`povagent.results.official_format.read_official_run`) are counted
exactly as the official scorer (``evaluation/eval_results.py``) counts them:

- every row counts in ``n_total``; a row is answered only when it has ``predicted_x`` and
  ``predicted_y``, names a pair of the dataset, and a placement for its direction; an A/B row
  also needs a ``predicted_image`` that is a path of the house's exploration log (when the log
  repeats a path, its last record). ``parse_error`` is not looked at;
- rows are grouped by their ``type`` and ``direction`` exactly as written: ``"A"`` is its own
  group, and every type other than ``"c"`` is scored as an A/B answer in its selected frame;
  ``"Front"`` names no placement and is counted unanswered;
- A/B pixels are divided by the metadata's ``screen_width``/``screen_height`` (512 when
  absent), also used for the selected frame's projection; C pixels by the observer camera's
  size, the metadata's when the camera has none;
- an infinite coordinate is clamped to the edge; a NaN one gives a NaN error;
- several ``predicted_points``: each is clamped, the centroid is scored, the closest point's
  error is kept beside it.

Each odd case is reported in a warning naming the rows. Several runs (an official prediction
root with one folder per run, files declaring ``metadata.run``, or our rows) are aggregated
by :func:`povagent.scoring.breakdown.breakdown`: the mean of per-run means, the paper's way.
Our results rows are re-scored from their stored prediction by
:func:`povagent.results.prediction_files.score_result_rows`, which reads them as the official
runner would and scores each with this room's rules.
"""

from __future__ import annotations

import json
import math
import re
from collections import defaultdict
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any, TypeGuard

from povagent.dataset.loader import Dataset, observer_camera
from povagent.dataset.release_models import CONDITIONS, DIRECTIONS
from povagent.scoring.normalized_l2 import (
    MAX_L2,
    GroundTruthInFrame,
    OfficialScore,
    point_errors,
    points_l2,
    project_ground_truth,
)
from povagent.scoring.official_release import NO_CAMERA, NotScorable, OfficialRelease

#: The fields the official scorer reads from every row (a row without one of them stops it).
REQUIRED_FIELDS = ("house_id", "pair_id", "direction", "type")
REQUIRED_KEYS = frozenset(REQUIRED_FIELDS)

#: The condition and direction labels of the paper (any other is counted as its own group).
CONDITION_LABELS = frozenset(str(c) for c in CONDITIONS)
DIRECTION_LABELS = frozenset(str(d) for d in DIRECTIONS)

#: Why the official scorer leaves a row unanswered, in the order it checks (its status names).
NO_PREDICTION = "no_prediction"
ENTRY_NOT_FOUND = "entry_not_found"
PLACEMENT_NOT_FOUND = "placement_not_found"
NO_SELECTED_IMAGE = "no_selected_image"
IMAGE_NOT_IN_LOG = "image_not_in_log"
NO_GT_POSITION = "no_gt_position"
#: Not an official status: a coordinate the official scorer cannot divide (it would stop).
NOT_A_NUMBER = "coordinate_not_a_number"

#: An official run folder's name: optional ``POVBench_`` prefix, the model, ``_<run>``.
RUN_FOLDER_NAME = re.compile(r"^(.*)_(\d+)$")
#: Run folders whose name ends so are comparisons, not runs (skipped as officially).
SKIPPED_RUN_FOLDER_SUFFIX = "_vs"


@dataclass(frozen=True)
class ScoredPrediction:
    """One prediction with its official score.

    ``condition`` and ``direction`` are the row's group labels as written (``None`` when the
    row has none: it then counts overall only); ``instance_id`` names what the row answers.
    """

    instance_id: str | None
    condition: str | None
    direction: str | None
    run: int
    score: OfficialScore
    l2_closest: float | None = None
    #: The row carries a (truthy) ``parse_error``, as the official summary counts them.
    parse_error: bool = False


# -- official rows ----------------------------------------------------------------------------


def group_label(value: Any) -> str | None:
    """A row's ``type`` or ``direction`` as the official summary keys it: a string as written,
    another scalar as JSON writes a key (``1`` -> ``"1"``), ``None`` for no group."""
    if value is None or isinstance(value, str):
        return value
    return json.dumps(value)


def _is_number(v: Any) -> bool:
    # bool is a number to the official scorer (True / 512 is 1/512)
    return isinstance(v, (int, float))


def _pair_key(pair_id: Any) -> str | None:
    """The dataset key of a row's pair id: the loader stores integer ids as strings."""
    if isinstance(pair_id, bool):
        return None
    if isinstance(pair_id, int):
        return str(pair_id)
    return pair_id if isinstance(pair_id, str) else None


def unanswered(status: str) -> OfficialScore:
    """The score of a row that is not scored, with the official status saying why."""
    return OfficialScore(False, None, None, None, None, None, None, status)


@dataclass
class _Notes:
    """Odd rows met while scoring, for the warnings (row references per kind)."""

    unknown: list[str]
    odd_type: dict[str, list[str]]
    odd_direction: dict[str, list[str]]
    nan: list[str]
    infinite: list[str]
    not_number: list[str]
    skipped: list[str]

    @classmethod
    def empty(cls) -> _Notes:
        return cls([], defaultdict(list), defaultdict(list), [], [], [], [])


def listing(refs: list[str], limit: int = 5) -> str:
    shown = ", ".join(refs[:limit])
    return shown + (f" and {len(refs) - limit} more" if len(refs) > limit else "")


def _warnings_of(notes: _Notes) -> list[str]:
    out: list[str] = []
    if notes.skipped:
        out.append(
            f"{len(notes.skipped)} row(s) skipped: not an object with {', '.join(REQUIRED_FIELDS)} "
            f"(the official scorer stops at such a row): {listing(notes.skipped)}"
        )
    if notes.unknown:
        out.append(
            f"{len(notes.unknown)} row(s) name a house, pair or placement the dataset does not have; "
            f"counted in the total as unanswered, as officially: {listing(notes.unknown)}"
        )
    for label, refs in notes.odd_type.items():
        how = "scored in the observer view" if label == "c" else "scored as an A/B answer in its selected frame"
        out.append(
            f"{len(refs)} row(s) with type {label!r}, not one of 'a', 'b', 'c': counted as their own "
            f"condition {label!r} and {how}, as officially (nothing is normalised): {listing(refs)}"
        )
    for label, refs in notes.odd_direction.items():
        out.append(
            f"{len(refs)} row(s) with direction {label!r}, not one of right, left, front, up: counted as their "
            f"own direction {label!r}, unanswered unless the pair has a placement of that exact name, as "
            f"officially: {listing(refs)}"
        )
    if notes.infinite:
        out.append(f"{len(notes.infinite)} row(s) with an infinite coordinate: clamped to the image edge, as officially: {listing(notes.infinite)}")
    if notes.nan:
        out.append(
            f"{len(notes.nan)} row(s) with a NaN coordinate: scored with a NaN error, so every mean over them "
            f"is NaN, as the official scorer records it: {listing(notes.nan)}"
        )
    if notes.not_number:
        out.append(
            f"{len(notes.not_number)} row(s) with a coordinate that is not a number: counted unanswered (the "
            f"official scorer cannot divide it and stops): {listing(notes.not_number)}"
        )
    return out


def _is_mapping(v: Any) -> TypeGuard[Mapping[Any, Any]]:
    # a JSON object is a dict: the abstract-class check only for anything else
    return type(v) is dict or isinstance(v, Mapping)


def _hashable(v: Any) -> bool:
    if type(v) is str:  # what every row holds: no need to hash it
        return True
    try:
        hash(v)
    except TypeError:
        return False
    return True


def _row_labels(row: Mapping[str, Any], notes: _Notes, ref: str | None) -> tuple[Any, Any, Any, Any, str | None, str | None, str]:
    """``(house_id, pair_id, direction, condition, condition label, direction label, instance
    id)`` of an official row, the first four as written; an odd condition or direction label is
    noted under ``ref`` (or the id)."""
    house_id, pair_id, direction, cond = row["house_id"], row["pair_id"], row["direction"], row["type"]  # REQUIRED_FIELDS
    # a label is a string as written (every row of the release): group_label for anything else
    c_label = cond if type(cond) is str else group_label(cond)
    d_label = direction if type(direction) is str else group_label(direction)
    iid = f"{house_id}/{pair_id}/{d_label}/{c_label}"
    if c_label is not None and c_label not in CONDITION_LABELS:
        notes.odd_type[c_label].append(ref or iid)
    if d_label is not None and d_label not in DIRECTION_LABELS:
        notes.odd_direction[d_label].append(ref or iid)
    return house_id, pair_id, direction, cond, c_label, d_label, iid


def score_official_row(
    row: Mapping[str, Any], dataset: Dataset, screen: tuple[float, float] = (512.0, 512.0), run: int = 0, ref: str = "", notes: _Notes | None = None
) -> ScoredPrediction:
    """Score one official row (a mapping as written) the way the official scorer does.

    ``screen`` is the metadata's ``(screen_width, screen_height)``; ``ref`` names the row in
    warnings collected in ``notes``.
    """
    notes = notes if notes is not None else _Notes.empty()
    house_id, pair_id, direction, cond, c_label, d_label, iid = _row_labels(row, notes, ref)

    def result(score: OfficialScore, closest: float | None = None) -> ScoredPrediction:
        return ScoredPrediction(iid, c_label, d_label, run, score, closest, bool(row.get("parse_error")))

    house = dataset.houses.get(house_id) if isinstance(house_id, str) else None
    pair_key = _pair_key(pair_id)
    pair = house.pairs.get(pair_key) if house is not None and pair_key is not None else None
    placement = pair.placements.get(direction) if pair is not None and _hashable(direction) else None
    if placement is None:
        notes.unknown.append(f"{ref} ({iid})" if ref else iid)

    x, y = row.get("predicted_x"), row.get("predicted_y")
    if x is None or y is None:
        return result(unanswered(NO_PREDICTION))
    if pair is None:
        return result(unanswered(ENTRY_NOT_FOUND))
    if placement is None:
        return result(unanswered(PLACEMENT_NOT_FOUND))
    sw, sh = screen
    if cond == "c":
        cam = observer_camera(pair)
        # the observer camera's own size wins; the metadata's only fills in a missing one
        given = pair.camera.model_fields_set
        camera = replace(
            cam,
            # the metadata's size is used as given (a float divides pixels just as well)
            width=cam.width if "screen_width" in given else sw,  # type: ignore[arg-type]
            height=cam.height if "screen_height" in given else sh,  # type: ignore[arg-type]
        )
    else:
        image = row.get("predicted_image")
        if not image:
            return result(unanswered(NO_SELECTED_IMAGE))
        frame = house.frames_by_path.get(image) if isinstance(image, str) else None  # type: ignore[union-attr]  # a pair was found, so its house was
        if frame is None:
            return result(unanswered(IMAGE_NOT_IN_LOG))
        # the selected frame is projected at the metadata's size, as officially
        camera = replace(frame.camera, width=sw, height=sh)
    found = house  # a pair was found, so its house was

    def ground_truth() -> GroundTruthInFrame:
        return project_ground_truth(dataset.target(found.house_id, pair, direction), camera)  # type: ignore[union-attr]

    return _score_recorded_point(row, x, y, ground_truth, camera.width, camera.height, notes, ref or iid, result)


def score_release_row(
    row: Mapping[str, Any], release: OfficialRelease, screen: tuple[float, float] = (512.0, 512.0), run: int = 0, ref: str = "", notes: _Notes | None = None
) -> ScoredPrediction:
    """Score one official row exactly as ``eval_results.py`` counts it, against the release as
    it indexes it (:mod:`povagent.scoring.official_release`): the pair id as written, the
    selected frame by its ``image_path`` as written, every field's official default.

    A value the official scorer would stop on is counted unanswered and named in ``notes``.
    """
    notes = notes if notes is not None else _Notes.empty()
    house_id, pair_id, direction, cond, c_label, d_label, iid = _row_labels(row, notes, ref)

    def result(score: OfficialScore, closest: float | None = None) -> ScoredPrediction:
        return ScoredPrediction(iid, c_label, d_label, run, score, closest, bool(row.get("parse_error")))

    x, y = row.get("predicted_x"), row.get("predicted_y")
    entry = release.entry(house_id, pair_id)
    placements = entry.get("placements", {}) if entry is not None else None
    placement = placements.get(direction) if _is_mapping(placements) and _hashable(direction) else None
    if not placement:
        notes.unknown.append(f"{ref} ({iid})" if ref else iid)
    if x is None or y is None:
        return result(unanswered(NO_PREDICTION))
    if entry is None:
        return result(unanswered(ENTRY_NOT_FOUND))
    if not placement:
        return result(unanswered(PLACEMENT_NOT_FOUND))
    try:
        raw_position = placement.get("position") if _is_mapping(placement) else None
        if not raw_position:
            return result(unanswered(NO_GT_POSITION))
        target = release.target(entry, direction, raw_position)
        sw, sh = screen
        if cond == "c":
            cam = release.camera(entry.get("camera", NO_CAMERA), "camera")
            width, height = (cam.width if cam.width is not None else sw), (cam.height if cam.height is not None else sh)
        else:
            image = row.get("predicted_image")
            if not image:
                return result(unanswered(NO_SELECTED_IMAGE))
            record = release.log(house_id).get(image) if isinstance(house_id, str) and _hashable(image) else None
            if record is None:
                return result(unanswered(IMAGE_NOT_IN_LOG))
            # the selected frame is projected at the metadata's size, as officially
            cam, (width, height) = release.camera(record.get("camera", NO_CAMERA), "camera"), (sw, sh)
        gt = release.ground_truth_in(target, cam, width, height)
    except NotScorable as exc:
        notes.not_number.append(f"{ref or iid} ({exc})")
        return result(unanswered(NOT_A_NUMBER))
    return _score_recorded_point(row, x, y, lambda: gt, width, height, notes, ref or iid, result)


def _score_recorded_point(
    row: Mapping[str, Any],
    x: Any,
    y: Any,
    ground_truth: Callable[[], GroundTruthInFrame],
    width: float,
    height: float,
    notes: _Notes,
    name: str,
    result: Callable[..., ScoredPrediction],
) -> ScoredPrediction:
    """The tail both countings share, once the frame and its size are known: a coordinate that
    is no number is unanswered; NaN and infinite ones are noted and scored as officially; the
    signed errors are the recorded point's (a point list's first), the L2 a point list's
    closest. ``ground_truth`` is asked for only when the point is a number."""
    if not (_is_number(x) and _is_number(y)):
        notes.not_number.append(name)
        return result(unanswered(NOT_A_NUMBER))
    x, y = float(x), float(y)
    if math.isnan(x) or math.isnan(y):
        notes.nan.append(name)
    elif math.isinf(x) or math.isinf(y):
        notes.infinite.append(name)
    gt = ground_truth()
    l2, ex, ey = point_errors(x, y, width, height, gt.u, gt.v)
    closest = None
    points = row.get("predicted_points")
    if points:
        try:
            l2, closest = points_l2([(p[0], p[1]) for p in points], width, height, gt.u, gt.v)
        except (TypeError, ValueError, IndexError, KeyError, ZeroDivisionError):
            notes.not_number.append(f"{name} (predicted_points)")
    strict = l2 if gt.in_frame else MAX_L2
    return result(OfficialScore(True, l2, strict, gt.in_frame, gt.behind, gt.u, gt.v, "ok", ex, ey), closest)


def score_official_rows(
    rows: Iterable[Any],
    dataset: Dataset | OfficialRelease,
    screen: tuple[float, float] = (512.0, 512.0),
    run: int = 0,
    refs: Sequence[str] | None = None,
) -> tuple[list[ScoredPrediction], list[str]]:
    """Score official rows (mappings as written); returns the scored rows (every row that has
    the official fields, answered or not) and the warnings. ``refs`` names each row in the
    warnings (``file: row i``, as the file reader knows them); ``row i`` when not given.

    Against an :class:`OfficialRelease` each row is counted exactly as officially
    (:func:`score_release_row`); against a loaded :class:`Dataset`, povagent's own counting
    (:func:`score_official_row`: only the pairs and frames the loader accepts, ids compared as
    text, ``./`` dropped from log paths)."""
    notes = _Notes.empty()
    scored: list[ScoredPrediction] = []
    for i, data in enumerate(rows):
        ref = refs[i] if refs is not None else f"row {i}"
        if not _is_mapping(data) or not data.keys() >= REQUIRED_KEYS:
            notes.skipped.append(ref)
            continue
        if not (_hashable(data["type"]) and _hashable(data["direction"])):
            notes.skipped.append(ref)
            continue
        if isinstance(dataset, OfficialRelease):
            scored.append(score_release_row(data, dataset, screen, run, ref, notes))
        else:
            scored.append(score_official_row(data, dataset, screen, run, ref, notes))
    return scored, _warnings_of(notes)
