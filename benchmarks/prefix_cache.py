"""House-major scheduling against a prefix cache: how often a house's 30 frames are reused.

The official prompt puts a house's 30 exploration frames first, so a server with automatic
prefix caching (vLLM's default) reuses them only while that house's prefix is still cached.
This replays the order in which the runner sends A/B requests (workers pull pending keys in
order, so the order requests reach the server is the pending order) against a model of such a
cache: an LRU of the prefixes of the ``K`` most recent houses (default 4). A request whose
house is cached is a hit; Given requests (one observer view each) do not touch the frame cache.

Orders compared, on the same instances:

- ``house-major``: povagent's order (:func:`povagent.run.pending.house_major`), fresh and after a
  resume with a random 40% of keys already done;
- ``condition-major``: every Inferred key, then every Stated key, then Given (what a loop over
  conditions, or a sweep with a condition axis run as one queue, sends);
- ``arrival (shuffled)``: keys in random order (many clients, or an unordered queue).

Usage::

    python benchmarks/prefix_cache.py [--dataset PATH] [--houses 47] [--k 4] [--runs 3]

Without ``--dataset`` it generates a paper-size set (47 houses, ``--jobs 2``) into a temporary
folder first (about two minutes on two idle cores).
"""

from __future__ import annotations

import argparse
import random
import tempfile
import time
from collections import OrderedDict
from pathlib import Path

from povagent.dataset.instances import Instance
from povagent.dataset.loader import load_dataset
from povagent.run.pending import house_major


def prefix_hit_rate(order: list[tuple[Instance, int]], k: int) -> tuple[float, int, int]:
    """``(hit rate, hits, A/B requests)`` of ``order`` against an LRU of ``k`` house prefixes."""
    cache: OrderedDict[str, None] = OrderedDict()
    hits = total = 0
    for instance, _run in order:
        if not instance.condition.uses_exploration_frames:
            continue
        total += 1
        house = instance.house_id
        if house in cache:
            hits += 1
            cache.move_to_end(house)
        else:
            cache[house] = None
            if len(cache) > k:
                cache.popitem(last=False)
    return (hits / total if total else float("nan")), hits, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset", type=Path, help="a POVBench-format dataset (default: generate one)")
    parser.add_argument("--houses", type=int, default=47)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--k", type=int, default=4, help="houses whose prefixes the cache holds")
    parser.add_argument("--runs", type=int, default=1, help="runs per instance (each a key)")
    args = parser.parse_args()

    root = args.dataset
    if root is None:
        from povagent.generate import generate_dataset

        root = Path(tempfile.mkdtemp(prefix="prefix_cache_")) / "POVBench"
        t = time.perf_counter()
        generate_dataset(root, houses=args.houses, seed=args.seed, frames=30, jobs=2)
        print(f"(generated {args.houses} houses in {time.perf_counter() - t:.0f} s: {root})")
    dataset = load_dataset(root)
    instances = dataset.instances()
    keys = [(i, r) for i in instances for r in range(args.runs)]
    rng = random.Random(args.seed)

    done = set(rng.sample(range(len(keys)), int(0.4 * len(keys))))
    resumed = [k for n, k in enumerate(keys) if n not in done]
    by_condition = sorted(keys, key=lambda k: k[0].condition.value)  # a, b, c: stable within
    shuffled = keys[:]
    rng.shuffle(shuffled)

    orders = {
        "house-major (povagent)": house_major(keys),
        "house-major after a resume (40% done)": house_major(resumed),
        "condition-major": by_condition,
        "arrival (shuffled)": shuffled,
    }
    n_houses = len(dataset.houses)
    print(f"{n_houses} houses, {len(keys)} keys ({args.runs} run(s)), LRU of K={args.k} house prefixes")
    print(f"{'order':42s} {'prefix hit rate':>16s} {'hits / A-B requests':>22s}")
    for name, order in orders.items():
        rate, hits, total = prefix_hit_rate(order, args.k)
        print(f"{name:42s} {100 * rate:15.1f}% {hits:>10d} / {total:<10d}")
    best = 1 - n_houses / sum(1 for i, _ in keys if i.condition.uses_exploration_frames)
    print(f"(the best any order can do: one miss per house, {100 * best:.1f}%)")


if __name__ == "__main__":
    main()
