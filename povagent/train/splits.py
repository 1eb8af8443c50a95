"""Splits by house: a house is in exactly one of train / validation / test.

Two ways to say it: ratios (``0.8,0.1,0.1``), where houses are ordered by a seeded hash of
their id and cut by largest remainders (so a house's split does not depend on which other houses
exist beyond the counts), or index ranges (``train=0:800,validation=800:900,test=900:1000``, half
open), where a house's index is the number in its id (``train_house_00042`` -> 42).
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

SPLITS = ("train", "validation", "test")
DEFAULT_SPLIT = "0.8,0.1,0.1"

_INDEX = re.compile(r"(\d+)$")
_BOUND = re.compile(r"[0-9]{1,12}")


class SplitError(ValueError):
    """A ``--split`` value that cannot be read."""


@dataclass(frozen=True)
class SplitSpec:
    """Either ``ratios`` (three shares summing to 1) or ``ranges`` (split -> [start, stop))."""

    ratios: tuple[float, float, float] | None = None
    ranges: tuple[tuple[str, int, int], ...] | None = None

    def __str__(self) -> str:
        if self.ratios is not None:
            return ",".join(f"{r:g}" for r in self.ratios)
        assert self.ranges is not None
        return ",".join(f"{name}={a}:{b}" for name, a, b in self.ranges)


def parse_split(text: str) -> SplitSpec:
    """Read ``0.8,0.1,0.1`` or ``train=0:800,test=800:1000``."""
    text = text.strip()
    if "=" not in text:
        try:
            values = [float(v) for v in text.split(",")]
        except ValueError:
            raise SplitError(f"--split {text!r}: give three shares (0.8,0.1,0.1) or ranges (train=0:800,test=800:900)") from None
        values += [0.0] * (3 - len(values))
        if len(values) != 3 or any(not math.isfinite(v) or v < 0 for v in values) or not math.isclose(sum(values), 1.0, abs_tol=1e-9):
            raise SplitError(f"--split {text!r}: up to three non-negative shares summing to 1 (train, validation, test)")
        return SplitSpec(ratios=(values[0], values[1], values[2]))
    ranges: list[tuple[str, int, int]] = []
    for item in text.split(","):
        name, _, span = item.partition("=")
        start, sep, stop = span.partition(":")
        name = name.strip()
        # ASCII digits of a sane length only: ``str.isdigit`` takes "²" and int() refuses
        # thousands of digits, both of which would end in a traceback
        if name not in SPLITS or not sep or not _BOUND.fullmatch(start.strip()) or not _BOUND.fullmatch(stop.strip()):
            raise SplitError(f"--split {item!r}: a range is NAME=START:STOP with NAME one of {', '.join(SPLITS)}")
        a, b = int(start), int(stop)
        if b <= a:
            raise SplitError(f"--split {item!r}: STOP must be greater than START")
        ranges.append((name, a, b))
    ordered = sorted(ranges, key=lambda r: r[1])
    for (n1, _, b1), (n2, a2, _) in itertools.pairwise(ordered):
        if a2 < b1:
            raise SplitError(f"--split: the ranges of {n1} and {n2} overlap: a house would be in two splits")
    return SplitSpec(ranges=tuple(ranges))


def house_index(house_id: str) -> int | None:
    """The number at the end of a house id, or ``None``."""
    match = _INDEX.search(house_id)
    return int(match.group(1)) if match else None


def _hash_key(seed: int, house_id: str) -> bytes:
    return hashlib.sha256(f"split\x00{seed}\x00{house_id}".encode()).digest()


def assign_splits(house_ids: Sequence[str], spec: SplitSpec, seed: int = 0) -> dict[str, str | None]:
    """Each house's split (``None``: outside every range, so not exported)."""
    if spec.ranges is not None:
        out: dict[str, str | None] = {}
        for hid in house_ids:
            idx = house_index(hid)
            out[hid] = next((name for name, a, b in spec.ranges if idx is not None and a <= idx < b), None)
        return out
    assert spec.ratios is not None
    n = len(house_ids)
    exact = [r * n for r in spec.ratios]
    counts = [math.floor(e) for e in exact]
    for i in sorted(range(3), key=lambda i: (counts[i] - exact[i], i))[: n - sum(counts)]:
        counts[i] += 1
    ordered = sorted(house_ids, key=lambda h: _hash_key(seed, h))
    out = {}
    start = 0
    for name, count in zip(SPLITS, counts):
        for hid in ordered[start : start + count]:
            out[hid] = name
        start += count
    return out
