"""How much the official metric's blind spot pays a center guess, measured on a dataset.

The official scorer places a GT that is behind the selected frame's camera at the image centre
(0.5, 0.5). So an Inferred/Stated answer that *selects a frame looking away from the target*
and points at the image centre scores 0. This script scores the center guess (W/2, H/2) under
several frame-selection policies, with the official metric and with the strict variant (a GT
behind the camera or outside the frame counts as a miss, sqrt 2):

- ``first``: frame 0 (the report's computed center baseline);
- ``random``: a uniformly random frame (averaged over all frames, i.e. its expectation);
- ``look-away``: a frame whose camera has the GT behind it, when the instance has one
  (otherwise frame 0): the exploit;
- ``in-frame``: a frame whose view contains the GT, when there is one (otherwise frame 0):
  an honest guess that at least looked the right way.

Usage::

    python benchmarks/blind_spot.py [--dataset PATH] [--houses N --seed S]

Without ``--dataset`` it generates a dataset with ``povagent.generate.generate_dataset`` when
that exists, else uses the hand-made fixture ``tests/fixtures/povbench_mini``. Prints one table
and the exploit's gain (official error of ``first`` minus that of ``look-away``).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from povagent.dataset.loader import load_dataset
from povagent.scoring.normalized_l2 import project_ground_truth, score_point

ROOT = Path(__file__).resolve().parent.parent
FIXTURE = ROOT / "tests" / "fixtures" / "povbench_mini"


def obtain_dataset(args: argparse.Namespace) -> Path:
    """The dataset to measure on: given, generated, or the fixture."""
    if args.dataset:
        return Path(args.dataset)
    try:
        from povagent.generate import generate_dataset  # type: ignore[attr-defined]
    except ImportError:
        print(f"(povagent.generate.generate_dataset not available: using {FIXTURE})")
        return FIXTURE
    out = Path(tempfile.mkdtemp(prefix="blind_spot_")) / "POVBench"
    t = time.perf_counter()
    generate_dataset(out, houses=args.houses, seed=args.seed, frames=args.frames)
    print(f"(generated {args.houses} houses in {time.perf_counter() - t:.1f} s: {out})")
    return out


def center_scores(instance, frame) -> tuple[float, float, float, float]:
    """(official, strict, GT in frame, GT behind) of the center guess in ``frame``."""
    w, h = instance.frame_size
    s = score_point(instance, frame, w / 2.0, h / 2.0)
    return s.l2, s.l2_strict, float(bool(s.gt_in_frame)), float(bool(s.gt_behind))


def measure(dataset) -> tuple[dict[str, dict[str, float]], dict[str, int]]:
    """Per policy: mean official and strict error, share of GT in the selected frame and of GT
    behind its camera, over the Inferred/Stated instances; plus counts."""
    policies = ("first", "random", "look-away", "in-frame")
    acc: dict[str, list[tuple[float, float, float, float]]] = {p: [] for p in policies}
    counts = {"instances": 0, "with_look_away_frame": 0, "with_in_frame_view": 0}
    for inst in dataset.instances(conditions=["a", "b"]):
        frames = inst.frames
        views = [project_ground_truth(inst.target, f.camera) for f in frames]
        away = [f for f, g in zip(frames, views) if g.behind]
        inside = [f for f, g in zip(frames, views) if g.in_frame]
        counts["instances"] += 1
        counts["with_look_away_frame"] += bool(away)
        counts["with_in_frame_view"] += bool(inside)
        per_frame = [center_scores(inst, f) for f in frames]
        acc["first"].append(per_frame[0])
        # the random policy's expectation: the mean over the frames it picks uniformly
        acc["random"].append(tuple(statistics.fmean(col) for col in zip(*per_frame)))  # type: ignore[arg-type]
        acc["look-away"].append(center_scores(inst, (away or frames)[0]))
        acc["in-frame"].append(center_scores(inst, (inside or frames)[0]))
    out = {
        p: dict(zip(("official", "strict", "gt_in_selected_frame", "gt_behind_camera"), (statistics.fmean(c) for c in zip(*rows))))
        for p, rows in acc.items()
    }
    return out, counts


def main(argv: list[str] | None = None) -> int:
    """Measure and print the table."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", help="dataset folder (release layout)")
    ap.add_argument("--houses", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--frames", type=int, default=30)
    args = ap.parse_args(argv)
    root = obtain_dataset(args)
    t = time.perf_counter()
    ds = load_dataset(root)
    res, counts = measure(ds)
    print(f"dataset {root}: {counts['instances']} Inferred/Stated instances; "
          f"{counts['with_look_away_frame']} have a frame with the GT behind the camera, "
          f"{counts['with_in_frame_view']} a frame with the GT in view ({time.perf_counter() - t:.2f} s)")
    print()
    print("| center guess, frame policy | official L2 | strict L2 | GT in selected frame | GT behind camera |")
    print("|---|---:|---:|---:|---:|")
    for p, r in res.items():
        print(f"| {p} | {r['official']:.3f} | {r['strict']:.3f} | {100 * r['gt_in_selected_frame']:.1f}% | {100 * r['gt_behind_camera']:.1f}% |")
    gain = res["first"]["official"] - res["look-away"]["official"]
    print()
    print(f"blind-spot gain of the center guess (official, first -> look-away frame): {gain:+.3f}; "
          f"strict closes it: {res['look-away']['strict']:.3f} vs {res['first']['strict']:.3f}")
    print(f"even a random frame pays: {100 * res['random']['gt_behind_camera']:.1f}% of its center guesses have the GT "
          f"behind the camera and score 0 (official {res['random']['official']:.3f}, strict {res['random']['strict']:.3f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
