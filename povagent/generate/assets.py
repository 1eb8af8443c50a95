"""ProcTHOR's asset and placement databases, read as plain JSON files.

What it is for: the real object sizes (each asset's bounding box) and the room-type frequencies
of the 31 observer/anchor categories, so generated furniture has ProcTHOR's dimensions and
belongs where ProcTHOR puts it. What it must not do: import ``procthor`` or ``ai2thor``
(importing ``procthor.databases`` imports ai2thor, which tries to download a Unity build), or
decide placements (that is ``furnishing``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib.metadata import distribution
from pathlib import Path
from typing import Callable

import numpy as np

#: The paper's 31 observer/anchor categories (its appendix table), as AI2-THOR object types.
OBSERVER_ANCHOR_CATEGORIES: tuple[str, ...] = (
    "ArmChair",
    "Bed",
    "Chair",
    "ClothesDryer",
    "CoffeeMachine",
    "CoffeeTable",
    "CounterTop",
    "Desk",
    "DeskLamp",
    "Desktop",
    "DiningTable",
    "Doorway",
    "Dresser",
    "Faucet",
    "FloorLamp",
    "Fridge",
    "GarbageCan",
    "HandTowelHolder",
    "HousePlant",
    "Microwave",
    "Safe",
    "ShelvingUnit",
    "SideTable",
    "Sink",
    "Sofa",
    "Stool",
    "Television",
    "Toaster",
    "Toilet",
    "TowelHolder",
    "WashingMachine",
)


@dataclass(frozen=True)
class AssetSpec:
    """One ProcTHOR asset: its id and bounding-box size in metres.

    ``size`` is ``(x, y, z)`` in the asset's own frame: width, height, depth; ProcTHOR assets
    face +z, so depth is front to back.
    """

    asset_id: str
    object_type: str
    size: tuple[float, float, float]

    @property
    def width(self) -> float:
        """Side-to-side extent (x)."""
        return self.size[0]

    @property
    def height(self) -> float:
        """Vertical extent (y)."""
        return self.size[1]

    @property
    def depth(self) -> float:
        """Front-to-back extent (z)."""
        return self.size[2]


def database_path(name: str) -> Path:
    """Path of one of the JSON databases shipped in the ``procthor`` wheel."""
    return Path(str(distribution("procthor").locate_file(f"procthor/databases/{name}")))


@lru_cache(maxsize=1)
def asset_database() -> dict[str, tuple[AssetSpec, ...]]:
    """Assets of the 31 categories, by object type, sorted by asset id (a stable order)."""
    raw = json.loads(database_path("asset-database.json").read_text())
    out: dict[str, tuple[AssetSpec, ...]] = {}
    for object_type in OBSERVER_ANCHOR_CATEGORIES:
        specs = []
        for entry in raw.get(object_type, []):
            box = entry["boundingBox"]
            size = (round(float(box["x"]), 4), round(float(box["y"]), 4), round(float(box["z"]), 4))
            specs.append(AssetSpec(str(entry["assetId"]), object_type, size))
        out[object_type] = tuple(sorted(specs, key=lambda s: s.asset_id))
    return out


@lru_cache(maxsize=1)
def placement_annotations() -> dict[str, dict[str, object]]:
    """ProcTHOR's placement annotations: column (``inKitchens``, ``onWall``...) -> type -> value."""
    return json.loads(database_path("placement-annotations.json").read_text())


def choose_asset(
    object_type: str,
    rng: np.random.Generator,
    fits: Callable[[AssetSpec], bool] | None = None,
) -> AssetSpec | None:
    """A random asset of ``object_type`` among those ``fits`` accepts; None if none does."""
    candidates = [a for a in asset_database()[object_type] if fits is None or fits(a)]
    if not candidates:
        return None
    return candidates[int(rng.integers(len(candidates)))]
