"""The order one annotator sees the instances in: shuffled, seeded, pairs kept apart.

A person learns: the second condition of a pair seen right after the first is answered from
memory, not from the frames. So the order is shuffled per annotator (seeded by the name and a
seed, the same on every resume) and two instances of one speaker-observer pair are never shown
back to back where the rest of the set allows it, unless ``pairs_apart`` is off.
"""

from __future__ import annotations

import hashlib
import random
from collections import Counter
from typing import Hashable, Sequence, TypeVar

from povagent.dataset.instances import Instance

K = TypeVar("K", bound=tuple[Instance, int])


def pair_of(key: tuple[Instance, int]) -> Hashable:
    """The speaker-observer pair a key belongs to: its house and pair (every direction and
    condition of the pair shows the same people in the same room)."""
    instance = key[0]
    return (instance.house_id, instance.pair_id)


def annotator_order(keys: Sequence[K], annotator: str, seed: int = 0, *, pairs_apart: bool = True) -> list[K]:
    """``keys`` in the annotator's order: a seeded shuffle (the same for the same name, seed and
    keys, whatever order they come in), then, with ``pairs_apart``, greedily re-spaced: each next
    key is the first in the shuffle whose pair differs from the last one's and after which the rest
    can still be spaced; when one pair holds too many for that, its keys go between the others
    first, so it follows itself no more often than it must."""
    digest = hashlib.sha256(f"{annotator}|{seed}".encode()).digest()
    ordered = sorted(keys, key=lambda k: (k[0].id, k[1]))
    random.Random(int.from_bytes(digest[:8], "big")).shuffle(ordered)
    if not pairs_apart:
        return ordered
    left = Counter(pair_of(k) for k in ordered)
    out: list[K] = []
    while ordered:
        last = pair_of(out[-1]) if out else None
        pick = next((i for i, k in enumerate(ordered) if pair_of(k) != last and _spaceable(left, pair_of(k))), None)
        if pick is None:  # one pair holds too many to space them all: spend it first, between the others
            crowded = max(left, key=lambda p: left[p])
            pick = next((i for i, k in enumerate(ordered) if pair_of(k) == crowded), 0) if crowded != last else \
                next((i for i, k in enumerate(ordered) if pair_of(k) != last), 0)
        key = ordered.pop(pick)
        left[pair_of(key)] -= 1
        out.append(key)
    return out


def _spaceable(left: Counter, pick: Hashable) -> bool:
    """Whether, after taking one key of ``pick``, what is left can still be laid out with no two
    neighbours of one pair when it follows a key of ``pick``: each pair at most half of it, rounded
    up, and ``pick`` itself at most half rounded down."""
    m = sum(left.values()) - 1
    for pair, count in left.items():
        n = count - 1 if pair == pick else count
        if n > (m // 2 if pair == pick else (m + 1) // 2):
            return False
    return True
