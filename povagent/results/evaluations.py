"""The official scorer's record of one item, for a result row (what ``eval_results.json`` holds).

The official evaluation writes, per prediction, a record: its ``status`` (``ok`` or why it was
not scored: ``no_prediction``, ``entry_not_found``, ``placement_not_found``,
``no_selected_image``, ``image_not_in_log``), the GT projected into the scored frame (clamped
to [0, 1], ``gt_in_frame``), the prediction normalized and clamped, the signed errors and the
L2; for multi-point answers the closest point's and the centroid's errors (the centroid's is
the L2). :func:`official_evaluation` builds that record from one of our rows, so the long CSV
(:mod:`povagent.report.export`) carries the numbers the official tools would.

The prediction is taken as the official runner would have recorded the same answer:
``parse_error`` is ``None`` when a point was read, ``"failed to parse JSON"`` when none was
(``"failed to parse points"`` for a RoboPoint answer, read by a ``robopoint`` parser), the
error message when the request failed; an A/B answer with a point but no usable frame keeps its
point and has no selected image. A multi-point answer (RoboPoint) records its *first* point as
``predicted_x``/``predicted_y``, as the runner did: the normalized prediction and ``error_x``/
``error_y`` are that point's, and only ``error_l2`` is the centroid's. Pure: rows and a loaded
dataset in, a dict out.
"""

from __future__ import annotations

import math
from typing import Any

from povagent.results.rows import ResultRow, RowStatus
from povagent.scoring.normalized_l2 import clamp_unit, points_l2, project_ground_truth

#: What the official runner records as ``parse_error`` when an answer has no readable point.
OFFICIAL_PARSE_FAILURE = "failed to parse JSON"
#: ... and when a RoboPoint answer has no ``(x, y)`` tuple.
OFFICIAL_POINTS_FAILURE = "failed to parse points"
#: Parsers of RoboPoint's point lists (their failures are recorded as the runner's RoboPoint path did).
POINT_LIST_PARSERS = frozenset({"robopoint", "robopoint-official"})


def raw_response(row: ResultRow) -> str:
    """The model's last raw answer in a row (``""`` when the request failed)."""
    for exchange in reversed(row.exchanges):
        if exchange.raw is not None:
            return exchange.raw
    return ""


def official_parse_error(row: ResultRow) -> str | None:
    """The ``parse_error`` the official runner would have recorded for this row's answer:
    ``None`` when it read a point (a point whose frame names no image included), the request's
    error when it failed, else its parse failure text."""
    if row.status == RowStatus.INFRA_ERROR:
        return row.error_message or row.error_type or "request failed"
    if row.status == RowStatus.ANSWERED and row.prediction.x is not None and row.prediction.y is not None:
        return None
    parse = row.parse
    if str(row.condition) != "c" and parse is not None and parse.x is not None and parse.y is not None:
        return None
    return OFFICIAL_POINTS_FAILURE if row.parser in POINT_LIST_PARSERS else OFFICIAL_PARSE_FAILURE


def _official_prediction(row: ResultRow, instance: Any) -> tuple[float | None, float | None, str | None, str | None, list[tuple[float, float]] | None]:
    """``(x, y, parse_error, predicted_image, points)`` as the official runner records them."""
    uses_frames = str(row.condition) != "c"
    p = row.prediction
    if row.status == RowStatus.ANSWERED and p.x is not None and p.y is not None:
        image = p.image_path
        if image is None and uses_frames and instance is not None:
            frame = instance.selected_frame(p.selected_image)
            image = frame.image_path if frame is not None else None
        points = [(float(a), float(b)) for a, b in row.parse.points] if row.parse is not None and row.parse.points else None
        # the runner recorded a point list's first point as the prediction (the centroid only
        # enters error_l2)
        x, y = points[0] if points else (float(p.x), float(p.y))
        return x, y, None, image if uses_frames else None, points
    parse = row.parse
    if row.status != RowStatus.INFRA_ERROR and uses_frames and parse is not None and parse.x is not None and parse.y is not None:
        # a point was read, but its frame index names no frame: officially a parsed answer
        # whose predicted_image is missing
        return float(parse.x), float(parse.y), None, None, None
    return None, None, official_parse_error(row), None, None


def official_evaluation(row: ResultRow, dataset: Any) -> dict[str, Any]:
    """The official evaluation record of one row against a loaded release-layout dataset.

    Keys present only when the official record has them (``gt_x`` ... ``error_l2`` once the item
    is scored, ``n_points``/``error_l2_min``/``error_l2_mean`` for multi-point answers,
    ``predicted_image``/``camera_image`` once known), so an absent value stays absent.
    """
    instance = dataset.instance(row.instance_id)
    x, y, parse_error, image, points = _official_prediction(row, instance)
    record: dict[str, Any] = {
        "pair_id": row.pair_id,
        "house_id": row.house_id,
        "direction": row.direction,
        "type": str(row.condition),
        "sentence": row.sentence,
        "predicted_x": x,
        "predicted_y": y,
        "parse_error": parse_error,
    }
    # the official checks, in its order: the first that fails names the status
    if x is None or y is None:
        return record | {"status": "no_prediction"}
    house = dataset.houses.get(row.house_id)
    if house is None or row.pair_id not in house.pairs:
        return record | {"status": "entry_not_found"}
    if instance is None:
        return record | {"status": "placement_not_found"}
    if instance.povbench_condition.uses_exploration_frames:
        if not image:
            return record | {"status": "no_selected_image"}
        record["predicted_image"] = image
        frame = instance.frame_by_path(image)
        if frame is None:
            return record | {"status": "image_not_in_log"}
        record["camera_image"] = image
    else:
        frame = instance.frames[0]
        record["camera_image"] = frame.image_path  # the pair's rgb_path
    cam = frame.camera
    gt = project_ground_truth(instance.target, cam)
    gx, gy = clamp_unit(gt.u), clamp_unit(gt.v)
    px, py = clamp_unit(x / cam.width), clamp_unit(y / cam.height)
    ex, ey = px - gx, py - gy
    record |= {
        "gt_x": gx,
        "gt_y": gy,
        "gt_in_frame": gt.in_frame,
        "predicted_x_norm": px,
        "predicted_y_norm": py,
        "error_x": ex,
        "error_y": ey,
        # sqrt of the sum, not hypot: the two can differ in the last bit, and the CSV is compared as text
        "error_l2": math.sqrt(ex * ex + ey * ey),
        "status": "ok",
    }
    if points:
        centroid, closest = points_l2(points, cam.width, cam.height, gt.u, gt.v)
        record["n_points"] = len(points)
        record["error_l2_min"] = closest
        record["error_l2_mean"] = record["error_l2"] = centroid
    return record
