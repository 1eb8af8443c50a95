"""The floor plan under a map from above: rooms, walls and doorways of a generated house.

What it is for: an active episode's trajectory means little on a blank page ("stopped by a
wall" where no wall is drawn). A povagent-generated house carries the record of what made it
(``_generated.json``: seed and index), and its floor plan is a pure function of those, so the
report rebuilds the plan alone (not the furniture, meshes or renderer: milliseconds) and draws
it under the path: each room's floor with its type, the walls as the generator built them (full
height slabs; a doorway is the gap between two), in grey. A house of any other set (the public
release carries no plan) simply has none. What it must not do: render views, score, or read
anything but the house's record (through :func:`povagent.active.house.check_generated`, which
refuses a name leading out of the dataset).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Callable
from xml.sax.saxutils import escape

from povagent.errors import DatasetError
from povagent.generate.floorplan import FloorPlan, Rect

#: Colours of a room's floor, its walls and its label.
FLOOR_COLOUR = "#eceff1"
WALL_COLOUR = "#78909c"
LABEL_COLOUR = "#90a4ae"
#: Words a room's type is labelled with.
ROOM_WORDS = {"LivingRoom": "living room", "Kitchen": "kitchen", "Bedroom": "bedroom", "Bathroom": "bathroom"}
#: Thinnest a wall is drawn (px), so an interior wall stays visible on a small map.
MIN_WALL_PX = 1.5

#: World (x, z) in metres to page (px, py).
Page = Callable[[float, float], tuple[float, float]]


def house_plan(dataset_root: Path | None, house_id: str) -> FloorPlan | None:
    """The floor plan of a povagent-generated house, or ``None`` when the house has no record
    this generator version reads (the public release, another generator version, no dataset)."""
    if dataset_root is None:
        return None
    return _plan(str(Path(dataset_root).resolve()), house_id)


@lru_cache(maxsize=32)
def _plan(root: str, house_id: str) -> FloorPlan | None:
    from povagent.active.house import check_generated
    from povagent.generate.floorplan import generate_floorplan
    from povagent.generate.house_pipeline import house_generators

    try:
        seed, index = check_generated(Path(root), house_id)
        return generate_floorplan(house_generators(seed, index)["plan"])
    except (DatasetError, ValueError, RuntimeError):  # no record, or one no generator run wrote (a negative seed)
        return None


def plan_points(plan: FloorPlan) -> list[tuple[float, float]]:
    """The footprint's corners, for fitting a map to the whole house."""
    f = plan.footprint
    return [(f.x0, f.z0), (f.x1, f.z1)]


def _rect(r: Rect, page: Page, fill: str, min_px: float = 0.0) -> str:
    (ax, ay), (bx, by) = page(r.x0, r.z0), page(r.x1, r.z1)
    x, y, w, h = min(ax, bx), min(ay, by), abs(bx - ax), abs(by - ay)
    if w < min_px:
        x, w = x - (min_px - w) / 2, min_px
    if h < min_px:
        y, h = y - (min_px - h) / 2, min_px
    return f'<rect x="{x:.1f}" y="{y:.1f}" width="{w:.1f}" height="{h:.1f}" fill="{fill}"/>'


def floor_plan_svg(plan: FloorPlan, page: Page) -> str:
    """The plan as an SVG group (``id="floor-plan"``): room floors and labels, then the walls."""
    parts = ['<g id="floor-plan">']
    for room in plan.rooms:
        parts.append(_rect(room.rect, page, FLOOR_COLOUR))
    for slab in plan.slabs:
        if slab.y0 == 0.0:  # a lintel over a doorway is no wall from above: the gap is the door
            parts.append(_rect(slab.rect, page, WALL_COLOUR, MIN_WALL_PX))
    for room in plan.rooms:
        cx, cy = page(*room.rect.center)
        word = ROOM_WORDS.get(room.room_type, room.room_type)
        parts.append(f'<text x="{cx:.1f}" y="{cy:.1f}" font-size="9" fill="{LABEL_COLOUR}" text-anchor="middle">{escape(word)}</text>')
    parts.append("</g>")
    return "".join(parts)
