"""The directions of POVBench, each held once: its name, its words and its rules.

A direction is a closed set's member that many rooms act on: the dataset's enum, the ground-truth
rule, the relation region, the counterfactual readings, the generator's judge and sentences, the
training facts and rationales, the geometric strategy's prompts, the report's filter and the
breakdown's order. Each of them reads the member's words and rules from :data:`DIRECTION_REGISTRY`
rather than comparing names, so adding a direction is one entry here (plus a generator version
bump, which :func:`generation_fingerprint` makes a test ask for).

The rules are data, read by the one function that applies each:

* :attr:`DirectionSpec.placement` (``on_top`` or ``beside``) and :attr:`DirectionSpec.axis` feed the
  official placement rule (:func:`povagent.geometry.ground_truth.target_point`): ``on_top`` puts
  the target on the anchor's top whatever the viewpoint; ``beside`` puts it outside the anchor's
  box along ``sign * basis``, where the basis is the observer's ``side`` axis (``right = up x
  forward``) or its ``forward`` axis (``normalize(anchor - observer)``, y zeroed);
* :attr:`DirectionSpec.may_stand_on_anchor`: the target may stand on a flat-topped anchor's top
  when the surface judgement names the anchor (the rule's ``c + 0.2 d`` case), read by
  :func:`povagent.geometry.ground_truth.stands_on_anchor`;
* :attr:`DirectionSpec.mirror`: the direction a left-right mirror turns it into.

Pure data: no numpy, no file, no other povagent module (the dataset's enum is built from it).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from enum import StrEnum


class Placement(StrEnum):
    """Where the official rule puts a target, before any offset."""

    #: On the anchor's top, at its xz centre, whatever the viewpoint.
    ON_TOP = "on_top"
    #: Outside the anchor's box along the direction's horizontal vector, on the supporting surface.
    BESIDE = "beside"


class Axis(StrEnum):
    """The observer's horizontal axis a ``beside`` direction runs along."""

    #: ``right = world_up x forward``: across the observer's line of sight.
    SIDE = "side"
    #: ``forward = normalize(anchor - observer)`` with y zeroed: along the line of sight.
    FORWARD = "forward"


@dataclass(frozen=True)
class DirectionSpec:
    """One direction: its name, its words and its rules (see the module docstring)."""

    #: The name in the release's files and instance ids (``stage3`` keys, ``pair_*`` folders).
    name: str
    #: The paper's wording of the relation: ``to the right of``, ``on top of``.
    paper_words: str
    #: The S-CoT prompt's relation word (step 4a): ``RIGHT``, ``ON TOP``.
    prompt_word: str
    #: The relation without its anchor, as a question names it: ``to the right``, ``on top``.
    short_words: str
    #: Words a model may answer for it (lower case, besides ``name``): ``above`` for ``up``.
    synonyms: tuple[str, ...]
    #: The generated sentence's relation; ``{anchor}`` is the anchor's name.
    sentence_phrase: str
    #: The sentence's relation when the target stands on the anchor's top (None: never said so).
    on_anchor_phrase: str | None
    #: The sentence's relation when the anchor is one sits or lies on (None: as ``sentence_phrase``).
    seat_phrase: str | None
    #: The official rule's placement.
    placement: Placement
    #: The observer axis a ``beside`` placement runs along, and its sign (None for ``on_top``).
    axis: tuple[Axis, float] | None
    #: May the target stand on a flat-topped anchor the surface judgement names?
    may_stand_on_anchor: bool
    #: The direction a left-right mirror turns this one into (itself when the mirror keeps it).
    mirror: str

    @property
    def vertical(self) -> bool:
        """On the anchor's top: the same target from every viewpoint."""
        return self.placement is Placement.ON_TOP

    @property
    def lateral(self) -> bool:
        """Across the observer's line of sight (left, right): the one a mirror swaps."""
        return self.axis is not None and self.axis[0] is Axis.SIDE

    @property
    def words(self) -> tuple[str, ...]:
        """Every word that names it in an answer: its name, then its synonyms."""
        return (self.name, *self.synonyms)


#: The directions, in the release's order (the generator's, the tables' and the breakdown's).
DIRECTION_REGISTRY: tuple[DirectionSpec, ...] = (
    DirectionSpec(
        name="right",
        paper_words="to the right of",
        prompt_word="RIGHT",
        short_words="to the right",
        synonyms=(),
        sentence_phrase="to the right of the {anchor}",
        on_anchor_phrase="on the right side of the {anchor}",
        seat_phrase=None,
        placement=Placement.BESIDE,
        axis=(Axis.SIDE, 1.0),
        may_stand_on_anchor=True,
        mirror="left",
    ),
    DirectionSpec(
        name="left",
        paper_words="to the left of",
        prompt_word="LEFT",
        short_words="to the left",
        synonyms=(),
        sentence_phrase="to the left of the {anchor}",
        on_anchor_phrase="on the left side of the {anchor}",
        seat_phrase=None,
        placement=Placement.BESIDE,
        axis=(Axis.SIDE, -1.0),
        may_stand_on_anchor=True,
        mirror="right",
    ),
    DirectionSpec(
        name="front",
        paper_words="in front of",
        prompt_word="FRONT",
        short_words="in front",
        synonyms=("in front",),
        sentence_phrase="in front of the {anchor}",
        on_anchor_phrase=None,
        seat_phrase=None,
        placement=Placement.BESIDE,
        axis=(Axis.FORWARD, -1.0),
        may_stand_on_anchor=False,
        mirror="front",
    ),
    DirectionSpec(
        name="up",
        paper_words="on top of",
        prompt_word="ON TOP",
        short_words="on top",
        synonyms=("above", "on top", "top"),
        sentence_phrase="on top of the {anchor}",
        on_anchor_phrase=None,
        seat_phrase="on the {anchor}",
        placement=Placement.ON_TOP,
        axis=None,
        may_stand_on_anchor=False,
        mirror="up",
    ),
)

#: The fields the generator's output depends on (the ground-truth rules and the sentence
#: phrases), which :func:`generation_fingerprint` hashes; the other words only reach prompts,
#: rationales and reports.
GENERATION_FIELDS = frozenset(
    {"name", "sentence_phrase", "on_anchor_phrase", "seat_phrase", "placement", "axis", "may_stand_on_anchor", "mirror"}
)

#: The names, in the registry's order.
DIRECTION_NAMES: tuple[str, ...] = tuple(spec.name for spec in DIRECTION_REGISTRY)

_BY_NAME = {spec.name: spec for spec in DIRECTION_REGISTRY}


def direction_spec(name: str) -> DirectionSpec | None:
    """The registry's entry for ``name`` (a ``Direction`` is a ``str``), or None when unknown."""
    return _BY_NAME.get(str(name))


def spec_of(name: str) -> DirectionSpec:
    """The registry's entry for a direction known to be in it (a ``Direction`` member)."""
    return _BY_NAME[str(name)]


def generation_fingerprint() -> str:
    """A hash of the registry's order and every field the generator's output depends on.

    ``povagent.generate.dataset`` pins it beside its ``GENERATOR_VERSION``; a test fails when the
    two disagree, so a change to a rule, a sentence phrase or the order comes with a version bump.
    """
    doc = [{k: v for k, v in asdict(spec).items() if k in GENERATION_FIELDS} for spec in DIRECTION_REGISTRY]
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]
