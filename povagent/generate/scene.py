"""The generated house as data: a floor plan plus placed objects.

What it is for: the one vocabulary the generator's rooms share (furnishing writes it, meshes,
renderer, exploration, pairs and writer read it), and the conversion of an object to the
release's ``object_*`` record. What it must not do: generate anything or touch files.

Objects are axis-aligned: their yaw is a multiple of 90 degrees, so the world box AI2-THOR
would report is exact. Local frame of an object: x across, y up, z front (+z faces out of the
object, towards whoever uses it); yaw turns local +z into world ``(sin yaw, 0, cos yaw)``,
the same convention as the camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from povagent.generate.floorplan import FloorPlan, Rect


@dataclass(frozen=True)
class PlacedObject:
    """One object of the 31 categories, placed in the house.

    ``center`` and ``size`` are the world axis-aligned box; ``local_size`` is (width, height,
    depth) before the yaw; ``support`` is the objectId of what it stands on, ``"floor"`` or
    ``"wall"``; ``style`` picks colours and shape variants for the mesh.
    """

    object_id: str
    object_type: str
    asset_id: str
    center: tuple[float, float, float]
    local_size: tuple[float, float, float]
    yaw: int
    room_id: int
    support: str = "floor"
    style: int = 0
    flags: tuple[str, ...] = field(default=())

    @property
    def size(self) -> tuple[float, float, float]:
        """World box size (x, y, z): width and depth swap at 90 and 270 degrees."""
        w, h, d = self.local_size
        return (d, h, w) if self.yaw % 180 == 90 else (w, h, d)

    @property
    def rect(self) -> Rect:
        """Footprint in the xz plane."""
        (cx, _, cz), (sx, _, sz) = self.center, self.size
        return Rect(cx - sx / 2, cz - sz / 2, cx + sx / 2, cz + sz / 2)

    @property
    def bottom(self) -> float:
        """Lowest y of the box."""
        return self.center[1] - self.local_size[1] / 2

    @property
    def top(self) -> float:
        """Highest y of the box."""
        return self.center[1] + self.local_size[1] / 2

    @property
    def front(self) -> np.ndarray:
        """Unit xz direction the object faces, as a 3-vector."""
        y = np.radians(self.yaw)
        return np.array([round(np.sin(y)), 0.0, round(np.cos(y))])

    def corner_points(self) -> list[list[float]]:
        """The 8 box corners, in AI2-THOR's order (top face first, then bottom)."""
        (cx, cy, cz), (sx, sy, sz) = self.center, self.size
        out = []
        for dy in (+1, -1):
            for dx, dz in ((+1, +1), (+1, -1), (-1, -1), (-1, +1)):
                out.append([cx + dx * sx / 2, cy + dy * sy / 2, cz + dz * sz / 2])
        return out

    def box_overlaps(self, lo: np.ndarray, hi: np.ndarray, tolerance: float = 0.01) -> bool:
        """True when this box overlaps the box [lo, hi] by more than ``tolerance`` on every axis."""
        c, s = np.asarray(self.center), np.asarray(self.size) / 2
        return bool(np.all(np.minimum(c + s, hi) - np.maximum(c - s, lo) > tolerance))

    def to_record(self) -> dict[str, Any]:
        """The release's ``object_landmark``/``object_observer`` record."""
        position = {"x": self.center[0], "y": self.center[1], "z": self.center[2]}
        size = dict(zip("xyz", self.size))
        return {
            "objectId": self.object_id,
            "assetId": self.asset_id,
            "position": position,
            "raw_metadata": {
                "objectType": self.object_type,
                "position": dict(position),
                "axisAlignedBoundingBox": {
                    "center": dict(position),
                    "size": size,
                    "cornerPoints": self.corner_points(),
                },
            },
        }


def object_id_for(object_type: str, center: tuple[float, float, float]) -> str:
    """An AI2-THOR style objectId: ``Type|+x.xx|+y.yy|+z.zz``."""
    x, y, z = center
    return f"{object_type}|{x:+.2f}|{y:+.2f}|{z:+.2f}"


@dataclass(frozen=True)
class House:
    """A furnished house: its id, plan and objects (in a fixed order: index = instance id - 1)."""

    house_id: str
    plan: FloorPlan
    objects: tuple[PlacedObject, ...]

    def by_id(self, object_id: str) -> PlacedObject:
        """The object with ``object_id``."""
        for o in self.objects:
            if o.object_id == object_id:
                return o
        raise KeyError(object_id)

    def count_of_type(self, object_type: str) -> int:
        """How many objects of ``object_type`` the house holds."""
        return sum(1 for o in self.objects if o.object_type == object_type)
