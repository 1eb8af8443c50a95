"""The directions registry: one entry per direction, and everything else derives from it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from povagent.dataset.release_models import DIRECTIONS, Direction
from povagent.generate.dataset import DIRECTIONS_FINGERPRINTS, GENERATOR_VERSION
from povagent.geometry.directions import (
    DIRECTION_NAMES,
    DIRECTION_REGISTRY,
    direction_spec,
    generation_fingerprint,
)

HERE = Path(__file__).resolve().parent


def test_the_generator_version_pins_the_registry_it_was_made_with():
    # A change to the registry's order, rules or sentence phrases changes the houses generated:
    # bump GENERATOR_VERSION and add its fingerprint to DIRECTIONS_FINGERPRINTS.
    assert DIRECTIONS_FINGERPRINTS.get(GENERATOR_VERSION) == generation_fingerprint()


def test_the_fingerprint_changes_when_the_order_changes(monkeypatch):
    import povagent.geometry.directions as registry

    before = generation_fingerprint()
    monkeypatch.setattr(registry, "DIRECTION_REGISTRY", DIRECTION_REGISTRY[::-1])
    assert generation_fingerprint() != before


def test_the_fingerprint_changes_when_a_rule_changes(monkeypatch):
    import dataclasses

    import povagent.geometry.directions as registry

    before = generation_fingerprint()
    bent = (dataclasses.replace(DIRECTION_REGISTRY[0], may_stand_on_anchor=False), *DIRECTION_REGISTRY[1:])
    monkeypatch.setattr(registry, "DIRECTION_REGISTRY", bent)
    assert generation_fingerprint() != before


def test_the_fingerprint_ignores_words_that_only_reach_prompts(monkeypatch):
    import dataclasses

    import povagent.geometry.directions as registry

    before = generation_fingerprint()
    reworded = (dataclasses.replace(DIRECTION_REGISTRY[0], synonyms=("starboard",)), *DIRECTION_REGISTRY[1:])
    monkeypatch.setattr(registry, "DIRECTION_REGISTRY", reworded)
    assert generation_fingerprint() == before


def test_the_dataset_enum_is_the_registry_in_its_order():
    assert [d.value for d in Direction] == list(DIRECTION_NAMES) == [str(d) for d in DIRECTIONS]
    assert DIRECTION_NAMES == ("right", "left", "front", "up")


def test_every_mirror_is_a_registered_direction_whose_mirror_is_the_first():
    for spec in DIRECTION_REGISTRY:
        other = direction_spec(spec.mirror)
        assert other is not None and other.mirror == spec.name


def test_only_lateral_directions_are_swapped_by_a_mirror():
    assert {s.name for s in DIRECTION_REGISTRY if s.mirror != s.name} == {s.name for s in DIRECTION_REGISTRY if s.lateral}


def test_a_beside_direction_has_an_axis_and_an_on_top_one_has_none():
    for spec in DIRECTION_REGISTRY:
        assert (spec.axis is None) == spec.vertical


def test_an_unknown_name_has_no_spec():
    assert direction_spec("diagonal") is None


def test_a_fifth_direction_in_the_registry_reaches_generation_ground_truth_scoring_and_the_report(tmp_path):
    proc = subprocess.run(
        [sys.executable, str(HERE / "fifth_direction.py"), str(tmp_path / "quickstart")],
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    seen = json.loads(proc.stdout.strip().splitlines()[-1])
    assert seen["directions"] == ["right", "left", "front", "up", "behind"]
    # ground truth: observer at z = -3 facing the anchor at the origin (half depth 0.3): the far side
    assert seen["gt"] == [0.0, 0.2, 0.5]
    # generation: the judge allows it and the sentence says it in the registry's words
    assert seen["given_sentences"] and all(" behind the " in s for s in seen["given_sentences"])
    # scoring: the oracle answers its ground truth, which scores (within rounding) zero
    assert seen["oracle_l2"] and max(seen["oracle_l2"]) < 1e-3
    # the report's filter and the per-direction breakdown, in the registry's order
    assert seen["page_has_filter_option"]
    assert seen["direction_header"].split("|")[2:7] == [" Right ", " Left ", " Front ", " Up ", " Behind "]
