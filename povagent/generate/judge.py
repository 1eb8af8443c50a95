"""Surface judges: is a target plausible in one direction of an anchor, and on which surface.

What it is for: stage 3 of the paper's pipeline. The paper asks a VLM, per (pair, direction),
whether a 0.4 m target can physically stand there and on what ("on the floor", "on the bed");
here a :class:`SurfaceJudge` protocol takes that place so a VLM judge can be plugged in, and
:class:`PhysicalRulesJudge` answers deterministically from the house geometry. Judges are
plugins: each is registered by name through the ``register_judges`` hook (the rules judge as
``physical-rules``, by the built-in ``povagent_plugins.judges.physical_rules``), and
:func:`create_judge` / :class:`RegisteredJudge` make one by that name. What it must not do:
compute the official ground truth itself (``povagent.geometry.ground_truth.target_point``
does) or validate against walls for the dataset (``pairs`` does that after judging).

The physical rules, for the surface the target would really stand on:
- up: the anchor has a flat top (a bed, a table, a counter, a seat, a fridge...) at least
  0.3 m across, and the space above its centre is free and under the ceiling;
- left/right on a flat-topped anchor of the scorer's set G: the spot offset 0.2 m from the
  centre is on the anchor's top and nothing else is there;
- otherwise (front, and left/right beside the anchor): the spot just past the anchor's box is
  on the floor (floor-standing anchors) or on the anchor's receptacle (a microwave's counter),
  inside the house, clear of walls and of every other object.

The spot is checked for an object of the pools' size (a book, a mug, boots: 0.3 m across, as
a person judging the photo would), not for the scorer's 0.4 m cube, which only sets offsets.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from povagent.errors import PluginError
from povagent.generate.floorplan import WALL_HEIGHT
from povagent.generate.scene import House, PlacedObject
from povagent.geometry.camera import Camera
from povagent.geometry.directions import spec_of
from povagent.geometry.ground_truth import AnchorBox, may_stand_on, target_point
from povagent.plugins import PluginHost, get_plugin_host

#: The judge the generator uses when none is named (registered by the built-in plugin).
DEFAULT_JUDGE = "physical-rules"

#: Half the size of the object checked for room at a spot: pool objects are about 0.3 m.
TARGET_FOOTPRINT_HALF = 0.15

APPROPRIATE = "appropriate"
INAPPROPRIATE = "inappropriate"

#: Anchors whose top a 0.4 m target can rest on.
UP_SURFACES = frozenset(
    {
        "ArmChair",
        "Bed",
        "Chair",
        "ClothesDryer",
        "CoffeeTable",
        "CounterTop",
        "Desk",
        "DiningTable",
        "Dresser",
        "Fridge",
        "Microwave",
        "Safe",
        "ShelvingUnit",
        "SideTable",
        "Sofa",
        "Stool",
        "Toilet",
        "WashingMachine",
    }
)

#: G members whose top is not a usable surface in practice (a monitor).
_NOT_REALLY_FLAT = frozenset({"Desktop"})

#: How surfaces are named in stage-3 phrases (the scorer's keyword match reads these).
SURFACE_NOUNS = {
    "ArmChair": "armchair",
    "CounterTop": "countertop",
}


def surface_noun(object_type: str) -> str:
    """Lower-case noun for a surface object: ``SideTable`` -> ``side table``."""
    if object_type in SURFACE_NOUNS:
        return SURFACE_NOUNS[object_type]
    return " ".join(w.lower() for w in re.findall(r"[A-Z][a-z]*", object_type))


@dataclass(frozen=True)
class SurfaceVerdict:
    """A stage-3 answer: ``verdict`` (``"appropriate"`` or not), the ``surface`` phrase, why."""

    verdict: str
    surface: str | None
    reason: str = ""

    @property
    def appropriate(self) -> bool:
        """True when a target may be placed."""
        return self.verdict == APPROPRIATE


@dataclass(frozen=True)
class JudgeRequest:
    """What a judge sees for one (pair, direction).

    ``image`` is the observer view (RGB, H x W x 3) for judges that look at it; the physical
    rules judge ignores it and reads ``house`` instead.
    """

    house: House
    observer: PlacedObject
    anchor: PlacedObject
    camera: Camera
    direction: str
    image: np.ndarray | None = None


@runtime_checkable
class SurfaceJudge(Protocol):
    """Stage 3: decide whether, and on which surface, a target fits one direction."""

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        """Return the verdict for ``request.direction`` of ``request.anchor``."""
        ...


def anchor_box(anchor: PlacedObject) -> AnchorBox:
    """The anchor's box as the official scorer reads it from the record."""
    (cx, _, cz), (sx, _, sz) = anchor.center, anchor.size
    return AnchorBox((cx, cz), (sx / 2.0, sz / 2.0), anchor.top)


def ground_truth(anchor: PlacedObject, camera: Camera, direction: str, verdict: SurfaceVerdict) -> np.ndarray:
    """The official ground-truth point for an appropriate verdict (``target_point``)."""
    anchor_pos = np.asarray(anchor.center)
    cam = np.asarray(camera.position)
    return target_point(
        direction,
        anchor_box(anchor),
        anchor.object_type,
        anchor_pos,
        cam,
        verdict.verdict,
        verdict.surface,
        raw_placement=np.zeros(3),
    )


def create_judge(name: str, options: Mapping[str, Any] | None = None, host: PluginHost | None = None) -> SurfaceJudge:
    """The judge registered as ``name`` (``register_judges``), made with ``options``.

    ``host`` defaults to the process-wide plugin host. An unknown name raises
    :class:`~povagent.errors.PluginError` with the nearest registered name; so does a factory
    that returns something without a ``judge(request)`` method.
    """
    host = host if host is not None else get_plugin_host()
    made = host.create("judge", name, options)
    if not isinstance(made, SurfaceJudge):
        source = host.entry("judge", name).source
        raise PluginError(
            f"judge {name!r} ({source}) made a {type(made).__name__}, which has no judge(request) method: "
            f"its factory must return a SurfaceJudge"
        )
    return made


class RegisteredJudge:
    """A registered judge by name: made through the plugin host in the process that uses it.

    ``generate_dataset`` hands this to its worker processes instead of a judge object: each
    worker loads ``plugins`` (and the built-in and entry-point plugins) itself and makes its
    own judge, so a judge need not pickle (a VLM judge's HTTP client, a judge defined in a
    ``.py`` plugin file) and is made once per process.
    """

    def __init__(self, name: str, options: Mapping[str, Any] | None = None, plugins: Sequence[str] = ()) -> None:
        self.name = name
        self.options = dict(options or {})
        self.plugins = tuple(plugins)
        self._judge: SurfaceJudge | None = None

    def resolve(self) -> SurfaceJudge:
        """The judge itself, made on first use (raises :class:`~povagent.errors.PluginError`)."""
        if self._judge is None:
            self._judge = create_judge(self.name, self.options, get_plugin_host(self.plugins))
        return self._judge

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        """The registered judge's verdict."""
        return self.resolve().judge(request)

    def __getstate__(self) -> dict[str, Any]:
        # The made judge stays in its process; the receiving process makes its own.
        return {**self.__dict__, "_judge": None}


def judge_name(judge: SurfaceJudge) -> str:
    """How ``meta.json`` names a judge object passed without a registered name: its ``name``
    attribute, else its class name."""
    return str(getattr(judge, "name", type(judge).__name__))


class PhysicalRulesJudge:
    """The deterministic judge: support, free space and clearance rules from the geometry."""

    name = "physical-rules"

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        """Try the plausible surfaces in order and return the first that holds a target."""
        anchor, house = request.anchor, request.house
        receptacle = None
        if anchor.support not in ("floor", "wall"):
            receptacle = house.by_id(anchor.support)
        if spec_of(request.direction).vertical:
            if anchor.object_type not in UP_SURFACES:
                return SurfaceVerdict(INAPPROPRIATE, None, "no flat top to stand on")
            sx, _, sz = anchor.size
            if min(sx, sz) < 0.3:
                return SurfaceVerdict(INAPPROPRIATE, None, "top too small")
            options: list[tuple[str, PlacedObject | None]] = [(f"on the {surface_noun(anchor.object_type)}", anchor)]
        else:
            options = []
            on_anchor_ok = may_stand_on(request.direction, anchor.object_type) and anchor.object_type not in _NOT_REALLY_FLAT
            if on_anchor_ok:
                options.append((f"on the {surface_noun(anchor.object_type)}", anchor))
            if receptacle is not None:
                options.append((f"on the {surface_noun(receptacle.object_type)}", receptacle))
            else:
                options.append(("on the floor", None))
        reasons = []
        for surface, support in options:
            verdict = SurfaceVerdict(APPROPRIATE, surface)
            gt = ground_truth(anchor, request.camera, request.direction, verdict)
            problem = self._problem(house, anchor, support, gt)
            if problem is None:
                return verdict
            reasons.append(f"{surface}: {problem}")
        return SurfaceVerdict(INAPPROPRIATE, None, "; ".join(reasons))

    def _problem(self, house: House, anchor: PlacedObject, support: PlacedObject | None, gt: np.ndarray) -> str | None:
        """Why a target at ``gt``'s xz, standing on ``support`` (None: the floor), cannot be there."""
        h = TARGET_FOOTPRINT_HALF
        x, z = float(gt[0]), float(gt[2])
        base = 0.0 if support is None else support.top
        if base + 2 * h > WALL_HEIGHT:
            return "no headroom"
        if support is None:
            if house.plan.room_at(x, z) is None:
                return "outside the house"
        elif not support.rect.inflate(-0.02).contains(x, z):
            return "not supported"
        centre = np.array([x, base + h, z])
        if house.plan.cube_hits_wall(centre, h) or not house.plan.cube_inside_house(centre, h):
            return "in a wall"
        lo, hi = centre - (h - 0.02), centre + (h - 0.02)
        for other in house.objects:
            # the spot lies off the anchor's box by construction; an axis-aligned test cube
            # only grazes its corner when the direction is oblique, which blocks nothing
            if other is support or other is anchor or other.object_type == "Doorway":
                continue
            if other.box_overlaps(lo, hi):
                return f"blocked by {other.object_type}"
        return None
