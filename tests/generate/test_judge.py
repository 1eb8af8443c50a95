"""The physical-rules surface judge on a hand-built room (one anchor, nothing else)."""

from __future__ import annotations

import numpy as np
import pytest

from povagent.generate.floorplan import FloorPlan, Rect, Room
from povagent.generate.judge import JudgeRequest, PhysicalRulesJudge
from povagent.generate.scene import House, PlacedObject
from povagent.geometry.camera import Camera


def _room_with(*objects: PlacedObject) -> House:
    rect = Rect(-3.0, -3.0, 3.0, 3.0)
    return House("h", FloorPlan(rect, (Room(0, "Bedroom", rect),), ()), objects)


DRESSER = PlacedObject("Dresser|0", "Dresser", "Dresser_1", (0.0, 0.4, 0.0), (1.2, 0.8, 0.5), 0, 0)


def _looking_at(anchor: PlacedObject, degrees: float, distance: float = 2.0) -> Camera:
    a = np.radians(degrees)
    x, z = anchor.center[0] + distance * np.sin(a), anchor.center[2] + distance * np.cos(a)
    yaw = float(np.degrees(np.arctan2(anchor.center[0] - x, anchor.center[2] - z)))
    return Camera((float(x), 1.55, float(z)), yaw, 30.0)


@pytest.mark.parametrize("degrees", [0.0, 30.0, 45.0, -60.0])
def test_the_floor_in_front_of_a_free_anchor_is_appropriate_from_any_side(degrees):
    house = _room_with(DRESSER)
    request = JudgeRequest(house, DRESSER, DRESSER, _looking_at(DRESSER, degrees), "front")
    verdict = PhysicalRulesJudge().judge(request)
    assert verdict.appropriate and verdict.surface == "on the floor", verdict.reason


def test_a_chair_on_the_spot_makes_the_front_inappropriate():
    chair = PlacedObject("Chair|0", "Chair", "Chair_1", (0.0, 0.45, 0.55), (0.5, 0.9, 0.5), 180, 0)
    house = _room_with(DRESSER, chair)
    verdict = PhysicalRulesJudge().judge(JudgeRequest(house, chair, DRESSER, _looking_at(DRESSER, 0.0), "front"))
    assert not verdict.appropriate and "Chair" in verdict.reason


def test_up_on_a_flat_top_names_the_anchor_itself():
    house = _room_with(DRESSER)
    verdict = PhysicalRulesJudge().judge(JudgeRequest(house, DRESSER, DRESSER, _looking_at(DRESSER, 0.0), "up"))
    assert verdict.appropriate and verdict.surface == "on the dresser"
