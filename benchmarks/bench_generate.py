"""Benchmark of the dataset generator: frame cost, quickstart time, paper-size estimate, directions.

Run: ``python benchmarks/bench_generate.py [--full]``. Prints, from measurements in this run:
seconds per rendered 512x512 frame on one core (wall and CPU), frames/s, the time of the
3-house quickstart set with ``--jobs 2``, the 47-house time with ``--jobs 2`` (estimated from
the quickstart's per-house cost, or measured with ``--full``), and the share of pairs per
direction against the paper's (front 97%, up 66%, left 62%, right 58%; 2.8 directions a pair).
Budgets: 0.25 s/frame, 30 s quickstart, 900 s for 47 houses.

``--compare`` measures only the cost of a house before and after (issue 28, item 5): CPU
seconds (``time.process_time``: the machine is shared) to generate one house with ``--jobs 1``
with today's code and with the ``povagent`` package of commit ``--baseline``, each in a fresh
interpreter (imports not counted), alternating round by round over ``--houses`` seeds; prints
CPU per house and houses per CPU-second of each, and the ratio.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

PAPER_SHARES = {"front": 0.97, "up": 0.66, "left": 0.62, "right": 0.58}
PAPER_DIRECTIONS_PER_PAIR = 2.8
PAPER_INSTANCES_PER_CONDITION = 813
PAPER_PAIRS = 288
#: The last commit before the cheaper houses (issue 28, item 5): the "before" of ``--compare``.
BEFORE = "43eae40"

ONE_HOUSE = """
import tempfile, time
from pathlib import Path
from povagent.generate import generate_dataset
with tempfile.TemporaryDirectory() as tmp:
    t = time.process_time()
    generate_dataset(Path(tmp), houses=1, seed={seed}, jobs=1, progress=False)
    print("cpu=", time.process_time() - t)
"""


def compare(baseline: str, houses: int) -> None:
    """CPU per house before (``baseline``) and after, alternating, one house per seed."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from baseline_code import baseline_checkout, cpu_of

    with tempfile.TemporaryDirectory() as tmp:
        old = baseline_checkout(baseline, Path(tmp) / "baseline")
        cpu: dict[str, list[float]] = {"before": [], "after": []}
        for seed in range(houses):
            order = (("before", old), ("after", None)) if seed % 2 == 0 else (("after", None), ("before", old))
            for label, path in order:
                cpu[label].append(cpu_of(ONE_HOUSE.format(seed=seed), path)["cpu"])
            print(f"  house seed {seed}: before {cpu['before'][-1]:.2f} s CPU, after {cpu['after'][-1]:.2f} s CPU, "
                  f"ratio {cpu['before'][-1] / cpu['after'][-1]:.2f}x")  # fmt: skip
    b, a = statistics.mean(cpu["before"]), statistics.mean(cpu["after"])
    print(f"CPU per house: before {b:.2f} s, after {a:.2f} s")
    print(f"houses per CPU-second: before {1 / b:.3f}, after {1 / a:.3f}: {b / a:.2f}x (goal >= 1.5x)")
    print(f"load average: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


def bench_frames(n: int = 20) -> tuple[float, float, float]:
    """(wall s/frame, CPU s/frame, PNG s/frame) over ``n`` exploration frames of one house."""
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house
    from povagent.generate.writer import write_png

    built = build_house(0, 0)
    cams = plan_tour(built.house, built.renderer, n)
    built.renderer.render(cams[0])  # warm the ray grid
    wall, cpu = time.perf_counter(), time.process_time()
    frames = [built.renderer.render(c) for c in cams]
    wall, cpu = (time.perf_counter() - wall) / len(cams), (time.process_time() - cpu) / len(cams)
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        for k, f in enumerate(frames):
            write_png(Path(tmp) / f"{k}.png", f.rgb)
        png = (time.perf_counter() - t) / len(frames)
    return wall, cpu, png


def bench_dataset(houses: int, jobs: int) -> tuple[float, object]:
    """Wall seconds to generate ``houses`` houses with ``jobs`` workers, and the report."""
    from povagent.generate import generate_dataset

    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        report = generate_dataset(Path(tmp), houses=houses, seed=0, jobs=jobs, progress=False)
        return time.perf_counter() - t, report


def print_directions(report) -> None:
    """Instances per direction and their shares of pairs, against the paper's."""
    shares, counts = report.direction_shares(), report.direction_counts()
    houses = len(report.houses)
    per_house = report.instances_per_condition / max(houses, 1)
    print(f"  pairs {report.pairs} ({report.pairs / max(houses, 1):.1f} per house; paper {PAPER_PAIRS / 47:.1f})")
    print(
        f"  instances per condition {report.instances_per_condition} ({per_house:.1f} per house, "
        f"{47 * per_house:.0f} for 47 houses; "
        f"paper {PAPER_INSTANCES_PER_CONDITION / 47:.1f} and {PAPER_INSTANCES_PER_CONDITION})"
    )
    for d in ("front", "up", "left", "right"):
        print(
            f"  {d:>5}: {counts[d]:4d} instances = {100 * shares[d]:5.1f}% of pairs   "
            f"(paper {100 * PAPER_SHARES[d]:.0f}%, {PAPER_SHARES[d] * PAPER_PAIRS:.0f} instances)"
        )
    per_pair = report.instances_per_condition / max(report.pairs, 1)
    print(f"  directions per pair: {per_pair:.2f}   (paper {PAPER_DIRECTIONS_PER_PAIR})")


def main() -> None:
    """Run the measurements and print them."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--full", action="store_true", help="measure 47 houses with --jobs 2 (minutes)")
    parser.add_argument("--sample", type=int, default=12, help="houses for the direction statistics")
    parser.add_argument("--compare", action="store_true", help="only CPU per house, before and after")
    parser.add_argument("--baseline", default=BEFORE, help=f"the commit timed as 'before' (default {BEFORE})")
    parser.add_argument("--houses", type=int, default=4, help="houses (seeds) measured by --compare")
    args = parser.parse_args()
    if args.compare:
        compare(args.baseline, args.houses)
        return
    print(f"cores: {os.cpu_count()}, load average: {os.getloadavg()[0]:.2f}")

    wall, cpu, png = bench_frames()
    print("\nrendering (512x512, one core, shadows on)")
    print(f"  {wall:.3f} s/frame wall, {cpu:.3f} s/frame CPU  -> {1 / wall:.1f} frames/s")
    print(f"  budget 0.25 s/frame: ratio {wall / 0.25:.2f}; PNG encoding adds {png:.3f} s/frame")

    quick, report = bench_dataset(3, 2)
    print("\nquickstart set: 3 houses, --jobs 2")
    print(f"  {quick:.1f} s for {report.renders} frames  -> budget 30 s: ratio {quick / 30:.2f}")

    one, one_report = bench_dataset(2, 1)
    per_house = one / 2
    estimate = per_house * 47 / 2
    print("\npaper size: 47 houses, --jobs 2")
    print(f"  one core: {per_house:.1f} s per house ({one_report.renders / 2:.0f} frames)")
    print(f"  estimate 47 houses on 2 cores: {estimate:.0f} s  -> budget 900 s: ratio {estimate / 900:.2f}")
    if args.full:
        full, full_report = bench_dataset(47, 2)
        print(f"  measured 47 houses on 2 cores: {full:.0f} s  -> budget 900 s: ratio {full / 900:.2f}")
        print(
            f"  instances per condition: {full_report.instances_per_condition} (paper {PAPER_INSTANCES_PER_CONDITION})"
        )
        sample_report = full_report
    else:
        _, sample_report = bench_dataset(args.sample, 2)

    print(f"\ndirections ({len(sample_report.houses)} houses)")
    print_directions(sample_report)
    rooms = np.array([h.rooms for h in sample_report.houses])
    print(f"  rooms per house: mean {rooms.mean():.1f}, range {rooms.min()}-{rooms.max()}")


if __name__ == "__main__":
    main()
