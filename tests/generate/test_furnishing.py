"""Furniture goes where ProcTHOR puts it, with ProcTHOR's sizes, and never into a doorway."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate.assets import asset_database, placement_annotations
from povagent.generate.floorplan import generate_floorplan
from povagent.generate.furnishing import furnish
from povagent.generate.house_pipeline import house_generators
from povagent.generate.scene import House

#: ProcTHOR places these on other objects, so its room annotations count them nowhere.
ON_RECEPTACLES = {"Television", "Sink", "Doorway"}


@pytest.fixture(scope="module")
def houses() -> list[House]:
    out = []
    for index in range(8):
        rngs = house_generators(5, index)
        plan = generate_floorplan(rngs["plan"])
        out.append(House(f"h{index}", plan, furnish(plan, rngs["furnish"])))
    return out


#: ProcTHOR's room types, as its placement annotations name their columns.
ROOM_TYPE_COLUMNS = {"Kitchen": "inKitchens", "LivingRoom": "inLivingRooms", "Bedroom": "inBedrooms", "Bathroom": "inBathrooms"}


def room_types_holding(object_type: str) -> list[str]:
    """Room types where ProcTHOR's placement annotations put ``object_type`` (0 never, 1
    sometimes, 2 often): the check the generator's own furnishing table is held to."""
    def frequency(room_type: str) -> int:
        value = placement_annotations().get(ROOM_TYPE_COLUMNS[room_type], {}).get(object_type)
        return int(value) if isinstance(value, (int, float)) else 0

    return [room_type for room_type in ROOM_TYPE_COLUMNS if frequency(room_type) > 0]


def test_every_object_stands_in_a_room_type_procthor_puts_it_in(houses):
    for house in houses:
        for o in house.objects:
            if o.object_type in ON_RECEPTACLES:
                continue
            assert house.plan.rooms[o.room_id].room_type in room_types_holding(o.object_type), o.object_id


def test_floor_furniture_footprints_do_not_overlap(houses):
    for house in houses:
        floor = [o for o in house.objects if o.support == "floor"]
        for i, a in enumerate(floor):
            for b in floor[i + 1 :]:
                assert not a.rect.overlaps(b.rect, tolerance=0.01), (a.object_id, b.object_id)


def test_objects_keep_their_procthor_asset_size(houses):
    sizes = {a.asset_id: a.size for specs in asset_database().values() for a in specs}
    for house in houses:
        for o in house.objects:
            if o.object_type in ("CounterTop", "Doorway"):
                continue
            assert tuple(round(v, 4) for v in o.local_size) == sizes[o.asset_id], o.object_id


def test_a_tv_faces_the_sofa_across_the_room(houses):
    seen = 0
    for house in houses:
        sofas = [o for o in house.objects if o.object_type == "Sofa"]
        tvs = [o for o in house.objects if o.object_type == "Television" and o.room_id == (sofas[0].room_id if sofas else -1)]
        for tv in tvs:
            assert (tv.yaw - sofas[0].yaw) % 360 == 180
            seen += 1
    assert seen > 0


def test_objects_on_receptacles_rest_on_their_top(houses):
    for house in houses:
        for o in house.objects:
            if o.support in ("floor", "wall"):
                continue
            holder = house.by_id(o.support)
            assert holder.rect.inflate(0.01).contains(*[o.center[0], o.center[2]])
            # centres are rounded to 0.1 mm; sinks sit down into their counter
            assert holder.top - 0.25 <= o.bottom <= holder.top + 1e-3


def test_chairs_are_drawn_up_to_the_dining_table_facing_it(houses):
    tables = 0
    for house in houses:
        chairs = [o for o in house.objects if o.object_type == "Chair"]
        for table in (o for o in house.objects if o.object_type == "DiningTable"):
            at_table = [c for c in chairs if table.rect.inflate(0.1).overlaps(c.rect.inflate(0.1))]
            assert at_table, table.object_id
            for chair in at_table:
                to_table = np.array([table.center[0] - chair.center[0], 0.0, table.center[2] - chair.center[2]])
                assert float(np.dot(chair.front, to_table / np.linalg.norm(to_table))) > 0.7, chair.object_id
            tables += 1
    assert tables >= len(houses) // 2  # most houses have a dining table, as ProcTHOR's do
