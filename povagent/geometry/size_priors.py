"""Typical sizes and heights of object types: the priors the geometric solver leans on.

What it is for: when an object is seen in one view only, its distance along the pointed ray is
fixed by how high its centre usually is; when its outline in the images is too poor to measure
its extent, its usual size stands in. Both come from ProcTHOR's own databases (read through
:mod:`povagent.generate.assets`, the files the generator furnishes houses from): each type's
median asset size, and where it stands (``onFloor``, ``onWall``, or on the receptacle that most
often holds it, per ``receptacles.json``). What it must not do: look at a dataset's records
(those are what is being estimated).
"""

from __future__ import annotations

import json
import statistics
from dataclasses import dataclass
from functools import cache, lru_cache
from typing import Any

#: Centre height (m) of wall-mounted types (towel holders): ProcTHOR gives no mounting height;
#: towel rails hang at about hand height.
WALL_MOUNT_HEIGHT = 1.15
#: Size (w, h, d) assumed for a type ProcTHOR does not know (a typical piece of furniture).
UNKNOWN_SIZE = (0.6, 0.8, 0.6)


@dataclass(frozen=True)
class SizePrior:
    """What an object of one type usually is: median size and how high its centre is.

    ``size`` is ``(width, height, depth)`` in metres (ProcTHOR's asset frame); ``support`` says
    what it stands on (``"floor"``, ``"wall"``, a receptacle type, or ``"unknown"``).
    """

    object_type: str
    size: tuple[float, float, float]
    centre_height: float
    support: str

    @property
    def half_height(self) -> float:
        """Half the median height."""
        return self.size[1] / 2.0


def _median_size(specs) -> tuple[float, float, float]:
    return tuple(float(statistics.median(s.size[i] for s in specs)) for i in range(3))  # type: ignore[return-value]


@lru_cache(maxsize=1)
def _receptacles() -> dict[str, dict]:
    from povagent.generate.assets import database_path

    return json.loads(database_path("receptacles.json").read_text())


def _all_sizes(object_type: str) -> tuple[float, float, float] | None:
    """Median size over every ProcTHOR asset of a type (not only the 31 categories)."""
    from povagent.generate.assets import asset_database

    known = asset_database().get(object_type)
    if known:
        return _median_size(known)
    return _raw_sizes().get(object_type)


@lru_cache(maxsize=1)
def _raw_sizes() -> dict[str, tuple[float, float, float]]:
    from povagent.generate.assets import database_path

    raw = json.loads(database_path("asset-database.json").read_text())
    out: dict[str, tuple[float, float, float]] = {}
    for object_type, entries in raw.items():
        boxes: list[dict[str, Any]] = [e["boundingBox"] for e in entries if isinstance(e, dict) and isinstance(e.get("boundingBox"), dict)]
        if boxes:
            x, y, z = (float(statistics.median(float(b[k]) for b in boxes)) for k in "xyz")
            out[object_type] = (x, y, z)
    return out


@cache
def size_prior(object_type: str) -> SizePrior:
    """The prior of ``object_type`` (a generic piece of floor furniture for an unknown type)."""
    from povagent.generate.assets import placement_annotations

    size = _all_sizes(object_type)
    if size is None:
        return SizePrior(object_type, UNKNOWN_SIZE, UNKNOWN_SIZE[1] / 2.0, "unknown")
    notes = placement_annotations()
    if notes.get("onWall", {}).get(object_type) is True:
        return SizePrior(object_type, size, WALL_MOUNT_HEIGHT, "wall")
    if notes.get("onFloor", {}).get(object_type) is not False:
        return SizePrior(object_type, size, size[1] / 2.0, "floor")
    holder = _usual_receptacle(object_type)
    if holder is None:
        return SizePrior(object_type, size, size[1] / 2.0, "floor")
    holder_size = _all_sizes(holder)
    base = holder_size[1] if holder_size is not None else 0.0
    return SizePrior(object_type, size, base + size[1] / 2.0, holder)


def _usual_receptacle(object_type: str) -> str | None:
    """The floor-standing receptacle that most often holds ``object_type`` (ProcTHOR's counts)."""
    from povagent.generate.assets import placement_annotations

    on_floor = placement_annotations().get("onFloor", {})
    best: tuple[float, str] | None = None
    for holder, contents in _receptacles().items():
        entry = contents.get(object_type) if isinstance(contents, dict) else None
        if not isinstance(entry, dict) or on_floor.get(holder) is not True:
            continue
        count = float(entry.get("count", 0) or 0)
        if best is None or count > best[0] or (count == best[0] and holder < best[1]):
            best = (count, holder)
    return best[1] if best else None
