"""One house, end to end: plan, furnish, mesh, explore, render, pair, write.

What it is for: the unit of work a worker process runs. ``build_house`` is the deterministic
part that needs no rendering (tests rebuild a written house from its seed with it);
``generate_house`` adds the tour, the frames, the pairs and the files. What it must not do:
share state between houses (each house has its own generators, so the output does not depend
on how houses are spread over processes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from povagent.generate.exploration import plan_tour
from povagent.generate.floorplan import generate_floorplan
from povagent.generate.furnishing import furnish
from povagent.generate.judge import PhysicalRulesJudge, SurfaceJudge
from povagent.generate.meshes import house_mesh
from povagent.generate.pairs import Pair, build_pairs
from povagent.generate.record import HouseSummary, house_id
from povagent.generate.renderer import Frame, Renderer
from povagent.generate.scene import House
from povagent.generate.writer import write_house

#: Pairs per house: the release has 288 pairs over 47 houses (6.1 a house).
PAIRS_PER_HOUSE = (5, 7)


def house_generators(seed: int, index: int) -> dict[str, np.random.Generator]:
    """Independent generators per stage of one house, from ``SeedSequence([seed, index])``.

    Seeding with the pair (seed, index) rather than ``seed + index`` keeps datasets of
    neighbouring seeds from sharing houses; one stream per stage keeps a change in one stage
    from reshuffling the others.
    """
    streams = np.random.SeedSequence([seed, index]).spawn(4)
    names = ("plan", "furnish", "paint", "pairs")
    return {n: np.random.Generator(np.random.PCG64(s)) for n, s in zip(names, streams)}


@dataclass
class BuiltHouse:
    """A house with its renderer, ready for cameras."""

    house: House
    renderer: Renderer
    rngs: dict[str, np.random.Generator]


def furnished_house(seed: int, index: int, rngs: dict[str, np.random.Generator] | None = None) -> House:
    """Plan and furnish house ``index`` of the dataset with ``seed``: the objects and their boxes,
    without meshes (milliseconds; the tasks read object positions from it)."""
    rngs = rngs if rngs is not None else house_generators(seed, index)
    plan = generate_floorplan(rngs["plan"])
    return House(house_id(index), plan, furnish(plan, rngs["furnish"]))


def build_house(seed: int, index: int, shadows: bool = True) -> BuiltHouse:
    """Plan, furnish and mesh house ``index`` of the dataset with ``seed``."""
    rngs = house_generators(seed, index)
    house = furnished_house(seed, index, rngs)
    renderer = Renderer(house, house_mesh(house, rngs["paint"]), shadows=shadows)
    return BuiltHouse(house, renderer, rngs)


def generate_house(
    folder: Path,
    seed: int,
    index: int,
    frames: int = 30,
    with_render: bool = False,
    judge: SurfaceJudge | None = None,
) -> HouseSummary:
    """Generate house ``index`` and write its files into ``folder``; returns its summary.

    ``folder`` is the house's own folder (``record.write_house_atomically`` hands a staging one).
    """
    built = build_house(seed, index)
    house, renderer = built.house, built.renderer
    cameras = plan_tour(house, renderer, frames)
    shots: list[Frame] = [renderer.render(c) for c in cameras]
    counts = [f.pixel_counts() for f in shots]
    rng = built.rngs["pairs"]
    max_pairs = int(rng.integers(PAIRS_PER_HOUSE[0], PAIRS_PER_HOUSE[1] + 1))
    pairs: list[Pair] = build_pairs(house, renderer, counts, judge or PhysicalRulesJudge(), rng, max_pairs)
    write_house(Path(folder), house, shots, pairs, with_render)
    directions: dict[str, int] = {}
    for p in pairs:
        for q in p.queries:
            directions[q.direction] = directions.get(q.direction, 0) + 1
    return HouseSummary(
        index=index,
        house_id=house.house_id,
        rooms=len(house.plan.rooms),
        objects=len(house.objects),
        reachable_frames=len(cameras),
        pairs=len(pairs),
        directions=directions,
        renders=len(shots) + len(pairs),
    )
