"""The bird's-eye view of a gallery card: the scene from above, drawn from the release's records.

So a reader sees at a glance whether a model chose a frame looking away from the target or
confused left and right: the boxes of every object the house's records hold (each pair's
observer and anchor), the observer (its camera, with its view direction) and the anchor
highlighted, the ground-truth target, the exploration cameras, the selected frame's camera with
its field of view, and the predicted pixel's ray down to the floor. For condition C the
selected camera is the observer view's.

Top view of AI2-THOR's left-handed, y-up world: x to the right and z up the page, so a camera's
right is the page's right when it faces up. Output is a small self-contained SVG (no scripts,
no external references). This module only draws: it never scores.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable
from xml.sax.saxutils import escape

import numpy as np

from povagent.files.confined_write import write_inside
from povagent.generate.floorplan import FloorPlan
from povagent.geometry.camera import Camera
from povagent.report.floor_plan import WALL_COLOUR, floor_plan_svg, house_plan, plan_points

#: Colours shared with the gallery's drawings (GT green, prediction red).
GT_COLOUR = "#00c853"
PRED_COLOUR = "#ff2d2d"
ANCHOR_COLOUR = "#2962ff"
OBSERVER_COLOUR = "#ff9100"
OBJECT_COLOUR = "#9e9e9e"
CAMERA_COLOUR = "#616161"
PATH_COLOUR = "#6200ea"
#: Size of the drawing (px), of the legend under it (px), and the margin around the scene (m).
VIEW_PX = 360
LEGEND_PX = 56
#: Height of one legend row (px): a legend of more than three rows makes the drawing taller.
LEGEND_ROW_PX = 13
MARGIN_M = 0.6
#: How far a ray that never reaches the floor is drawn (m).
RAY_LENGTH_M = 4.0
#: Length of the field-of-view wedge's sides (m).
FOV_LENGTH_M = 2.5


@dataclass(frozen=True)
class Box2D:
    """An object's footprint from above: type, id and the xz extent."""

    object_type: str
    object_id: str
    x0: float
    z0: float
    x1: float
    z1: float


@dataclass(frozen=True)
class BirdsEyeScene:
    """Everything one bird's-eye view shows, in world metres (x, z)."""

    objects: tuple[Box2D, ...]
    anchor_id: str
    observer_id: str
    observer_camera: Camera
    target: tuple[float, float, float]
    exploration: tuple[Camera, ...]
    selected: Camera | None
    prediction: tuple[float, float] | None
    title: str
    #: An active-mode episode's poses, start first: (x, z, yaw) each; empty for a passive row.
    path: tuple[tuple[float, float, float], ...] = ()
    #: The house's floor plan, drawn under everything (a generated house's, for an active row).
    plan: FloorPlan | None = None


def footprint(obj: Any) -> Box2D:
    """The xz footprint of a release ``SceneObject`` (from its box's corner points)."""
    corners = np.asarray(obj.raw_metadata.axisAlignedBoundingBox.cornerPoints, dtype=float)
    return Box2D(
        obj.object_type, str(obj.objectId), float(corners[:, 0].min()), float(corners[:, 2].min()), float(corners[:, 0].max()), float(corners[:, 2].max())
    )


def scene_for(instance: Any, house: Any, selected: Camera | None, prediction: tuple[float, float] | None) -> BirdsEyeScene:
    """The scene of one gallery row: ``house`` is the loaded house of ``instance`` (its pairs and
    exploration log), ``selected`` the camera the answer was scored in, ``prediction`` its pixel."""
    objects: dict[str, Box2D] = {}
    for pair in house.pairs.values():
        for obj in (pair.object_observer, pair.object_landmark):
            objects.setdefault(str(obj.objectId), footprint(obj))
    for obj in (instance.observer_object, instance.anchor_object):
        objects.setdefault(str(obj.objectId), footprint(obj))
    return BirdsEyeScene(
        objects=tuple(objects[k] for k in sorted(objects)),
        anchor_id=str(instance.anchor_object.objectId),
        observer_id=str(instance.observer_object.objectId),
        observer_camera=instance.observer_camera,
        target=tuple(float(v) for v in instance.target),  # type: ignore[arg-type]
        exploration=tuple(f.camera for f in house.frames),
        selected=selected,
        prediction=prediction,
        title=f"{instance.id}: {instance.direction} of the {instance.anchor_object.object_type}, seen from the {instance.observer_object.object_type}",
    )


def prediction_on_floor(camera: Camera, pixel: tuple[float, float]) -> tuple[np.ndarray, bool]:
    """Where the predicted pixel's ray meets the floor (``y = 0``), and whether it does; a ray
    that never does (pointing above the horizon) is cut at :data:`RAY_LENGTH_M`."""
    p = camera.point_on_plane(np.asarray(pixel, dtype=float), plane_y=0.0)
    if np.all(np.isfinite(p)):
        return p, True
    return np.asarray(camera.position) + RAY_LENGTH_M * camera.ray(np.asarray(pixel, dtype=float)), False


class _Frame:
    """World (x, z) to page (px): x right, z up, uniform scale, fitted to the scene."""

    def __init__(self, points: Iterable[tuple[float, float]]) -> None:
        pts = np.array(list(points), dtype=float)
        lo, hi = pts.min(axis=0) - MARGIN_M, pts.max(axis=0) + MARGIN_M
        self.lo, self.hi = lo, hi
        self.scale = VIEW_PX / max(hi[0] - lo[0], hi[1] - lo[1], 1e-6)

    def __call__(self, x: float, z: float) -> tuple[float, float]:
        return ((x - self.lo[0]) * self.scale, (self.hi[1] - z) * self.scale)

    def length(self, metres: float) -> float:
        return metres * self.scale


def _f(v: float) -> str:
    return f"{v:.1f}"


def _fov_wedge(camera: Camera, length: float) -> list[tuple[float, float]]:
    """Apex and the two far corners of a camera's horizontal field of view, in world xz."""
    half = math.radians(camera.fov) / 2.0 * (camera.width / camera.height)
    yaw = math.radians(camera.yaw)
    apex = (camera.position[0], camera.position[2])
    return [apex] + [(apex[0] + length * math.sin(yaw + s * half), apex[1] + length * math.cos(yaw + s * half)) for s in (-1, 1)]


def birds_eye_svg(scene: BirdsEyeScene) -> str:
    """The SVG of one scene (about 2-5 KB)."""
    pred_floor = None
    if scene.selected is not None and scene.prediction is not None:
        pred_floor = prediction_on_floor(scene.selected, scene.prediction)
    points = [(b.x0, b.z0) for b in scene.objects] + [(b.x1, b.z1) for b in scene.objects]
    points += [(c.position[0], c.position[2]) for c in (*scene.exploration, scene.observer_camera)]
    points.append((scene.target[0], scene.target[2]))
    if scene.selected is not None:
        points += _fov_wedge(scene.selected, FOV_LENGTH_M)
    if pred_floor is not None:
        points.append((float(pred_floor[0][0]), float(pred_floor[0][2])))
    points += [(x, z) for x, z, _ in scene.path]
    if scene.plan is not None:
        points += plan_points(scene.plan)
    page = _Frame(points)
    legend = [
        (GT_COLOUR, "GT target"),
        (PRED_COLOUR, "prediction's ray to the floor"),
        (ANCHOR_COLOUR, "anchor"),
        (OBSERVER_COLOUR, "observer"),
        ("#f9a825", "selected frame's view"),
    ]
    if scene.path:
        legend.append((PATH_COLOUR, "active episode's path and headings"))
    if scene.plan is not None:
        legend.append((WALL_COLOUR, "walls (a gap: a doorway)"))
    legend_px = LEGEND_PX + LEGEND_ROW_PX * max(0, (len(legend) + 1) // 2 - 3)  # three rows fit in LEGEND_PX
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{VIEW_PX}" height="{VIEW_PX + legend_px}" viewBox="0 0 {VIEW_PX} {VIEW_PX + legend_px}" '
        'font-family="sans-serif" font-size="10">',
        f"<title>{escape(scene.title)}</title>",
        f'<rect width="{VIEW_PX}" height="{VIEW_PX}" fill="#fafafa" stroke="#ccc"/>',
    ]
    if scene.plan is not None:
        out.append(floor_plan_svg(scene.plan, page))
    out.append('<g id="objects">')
    for b in scene.objects:
        (x0, y1), (x1, y0) = page(b.x0, b.z0), page(b.x1, b.z1)
        role = "anchor" if b.object_id == scene.anchor_id else "observer" if b.object_id == scene.observer_id else "object"
        colour = {"anchor": ANCHOR_COLOUR, "observer": OBSERVER_COLOUR}.get(role, OBJECT_COLOUR)
        fill_opacity = "0.35" if role != "object" else "0.15"
        out.append(
            f'<rect class="{role}" x="{_f(x0)}" y="{_f(y0)}" width="{_f(x1 - x0)}" height="{_f(y1 - y0)}" fill="{colour}" '
            f'fill-opacity="{fill_opacity}" stroke="{colour}"><title>{escape(b.object_type)}</title></rect>'
        )
    out.append("</g>")
    out.append('<g id="exploration-cameras">')
    for c in scene.exploration:
        x, y = page(c.position[0], c.position[2])
        out.append(f'<circle cx="{_f(x)}" cy="{_f(y)}" r="1.8" fill="{CAMERA_COLOUR}"/>')
    out.append("</g>")
    if scene.selected is not None:
        wedge = " ".join(f"{_f(px)},{_f(py)}" for px, py in (page(*p) for p in _fov_wedge(scene.selected, FOV_LENGTH_M)))
        out.append(f'<polygon id="fov" points="{wedge}" fill="#ffd54f" fill-opacity="0.3" stroke="#f9a825"/>')
    if scene.path:  # an active episode: where the robot went and which way each view looked
        out.append(_trajectory(scene.path, page))
    oc = scene.observer_camera
    ox, oy = page(oc.position[0], oc.position[2])
    yaw = math.radians(oc.yaw)
    tx, ty = page(oc.position[0] + 0.5 * math.sin(yaw), oc.position[2] + 0.5 * math.cos(yaw))
    out.append(
        f'<g id="observer"><line x1="{_f(ox)}" y1="{_f(oy)}" x2="{_f(tx)}" y2="{_f(ty)}" stroke="{OBSERVER_COLOUR}" stroke-width="2"/>'
        f'<circle cx="{_f(ox)}" cy="{_f(oy)}" r="4.5" fill="{OBSERVER_COLOUR}" stroke="#fff"/></g>'
    )
    if pred_floor is not None and scene.selected is not None:
        cx, cy = page(scene.selected.position[0], scene.selected.position[2])
        (px, _, pz), met = pred_floor
        ex, ey = page(float(px), float(pz))
        dash = "" if met else ' stroke-dasharray="4 3"'
        out.append(
            f'<g id="prediction"><line x1="{_f(cx)}" y1="{_f(cy)}" x2="{_f(ex)}" y2="{_f(ey)}" stroke="{PRED_COLOUR}" stroke-width="1.5"{dash}/>'
            f'<path d="M{_f(ex - 4)},{_f(ey - 4)}L{_f(ex + 4)},{_f(ey + 4)}M{_f(ex - 4)},{_f(ey + 4)}L{_f(ex + 4)},{_f(ey - 4)}" stroke="{PRED_COLOUR}" '
            'stroke-width="2"/></g>'
        )
    gx, gy = page(scene.target[0], scene.target[2])
    out.append(f'<circle id="target" cx="{_f(gx)}" cy="{_f(gy)}" r="5" fill="{GT_COLOUR}" stroke="#fff" stroke-width="1.5"/>')
    for i, (colour, text) in enumerate(legend):
        x, y = 4.0 + 180.0 * (i % 2), VIEW_PX + 8 + LEGEND_ROW_PX * (i // 2)
        out.append(f'<rect x="{_f(x)}" y="{y}" width="8" height="8" fill="{colour}"/><text x="{_f(x + 11)}" y="{y + 8}">{escape(text)}</text>')
    bar_y = VIEW_PX + legend_px - 6
    out.append(
        f'<line x1="6" y1="{bar_y}" x2="{_f(6 + page.length(1.0))}" y2="{bar_y}" stroke="#333" stroke-width="2"/>'
        f'<text x="{_f(10 + page.length(1.0))}" y="{bar_y + 3}">1 m (from above: x right, z up)</text>'
    )
    out.append("</svg>")
    return "\n".join(out)


def _trajectory(path: tuple[tuple[float, float, float], ...], page: _Frame) -> str:
    """The episode's path (a polyline through its poses) with a heading tick at each pose."""
    at = [page(x, z) for x, z, _ in path]
    parts = [
        '<g id="trajectory"><polyline points="'
        + " ".join(f"{_f(a)},{_f(b)}" for a, b in at)
        + f'" fill="none" stroke="{PATH_COLOUR}" stroke-width="1.5" stroke-dasharray="3 2"/>'
    ]
    for (x, z, yaw), (a, b) in zip(path, at):
        tx, ty = page(x + 0.3 * math.sin(math.radians(yaw)), z + 0.3 * math.cos(math.radians(yaw)))
        parts.append(f'<line x1="{_f(a)}" y1="{_f(b)}" x2="{_f(tx)}" y2="{_f(ty)}" stroke="{PATH_COLOUR}"/>')
    return "".join(parts) + "</g>"


def write_birds_eye(svg: str, images_dir: Path) -> str:
    """Save an SVG under ``images_dir`` as ``<sha256>.svg`` (kept if it exists); returns the hash."""
    key = hashlib.sha256(svg.encode()).hexdigest()
    path = images_dir / f"{key}.svg"
    if not path.exists():
        write_inside(images_dir, path.name, svg, unique=True)  # aside and renamed: a link planted there is replaced
    return key


def birds_eye_for_row(
    observation: Any,
    instance: Any,
    dataset: Any,
    images_dir: Path,
    frame: Any | None,
    path: tuple[tuple[float, float, float], ...] = (),
) -> str | None:
    """The bird's-eye file of one gallery row (its hash), or ``None`` where the records cannot
    draw one (a real-world set, a house the dataset does not hold). ``path`` is an active
    episode's poses (x, z, yaw), drawn as its trajectory."""
    house = getattr(dataset, "houses", {}).get(getattr(instance, "house_id", None))
    if house is None or not hasattr(instance, "observer_camera") or not hasattr(house, "pairs"):
        return None
    pred = (observation.x, observation.y) if observation.x is not None and observation.y is not None else None
    selected = frame.camera if frame is not None else None
    scene = scene_for(instance, house, selected, pred)
    if path:  # an active row: the walls the episode moved between, under its path
        scene = dataclasses.replace(scene, path=path, plan=house_plan(getattr(dataset, "root", None), instance.house_id))
    return write_birds_eye(birds_eye_svg(scene), images_dir)

