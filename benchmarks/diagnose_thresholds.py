"""Where the diagnostics' two thresholds come from: distributions on baseline runs.

Runs four offline systems over the Inferred and Stated instances of a generated set, scored with
``official`` and ``diagnose``:

- ``oracle``: the ground truth projected in the frame that shows it best (no noise);
- ``planted-0``: the ``planted`` simulation with every share 0 (the ground truth in a frame that
  shows the anchor, 5 px noise);
- ``center``: the image centre of a random frame;
- ``random``: a random pixel of a random frame.

and prints, for each, the distribution of ``anchor_distance`` (normalized distance from the
point to the anchor's box in the answered frame) and the share of answers beyond each candidate
anchor threshold: the threshold should keep every ground-truth answer and catch most blind
guesses. Then, for the egocentric-bias margin, how many ``planted-0`` answers are eligible and how
many of them (all answering the ground truth) would wrongly vote "egocentric" at each candidate
margin. Usage::

    python benchmarks/diagnose_thresholds.py [--dataset PATH | --houses N --seed S]
"""

from __future__ import annotations

import argparse
import asyncio
import math
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.results.rows import iter_rows
from povagent.run.runner import PipelineRun

ANCHOR_CANDIDATES = (0.05, 0.10, 0.15, 0.20, 0.25)
MARGIN_CANDIDATES = (0.0, 0.02, 0.05, 0.10)
SYSTEMS: dict[str, Any] = {
    "oracle": {"name": "oracle", "options": {}},
    "planted-0": {"name": "planted", "options": {"pixel_sigma": 5, "seed": 0}},
    "center": {"name": "center", "options": {"frame_policy": "random", "seed": 0}},
    "random": {"name": "random", "options": {"seed": 0}},
}


def dataset_path(args: argparse.Namespace, prefix: str = "diagnose_thresholds_") -> Path:
    """The dataset given (``--dataset``), or ``--houses`` houses of 30 frames freshly generated
    (``--seed``) into a new temporary folder named ``prefix...``."""
    if args.dataset:
        return Path(args.dataset)
    from povagent.generate import generate_dataset

    out = Path(tempfile.mkdtemp(prefix=prefix)) / "POVBench"
    generate_dataset(out, houses=args.houses, seed=args.seed, frames=30, progress=False)
    return out


def run_system(dataset: Path, backend: dict[str, Any], out: Path) -> list[dict[str, Any]]:
    """The diagnose scores of one offline system's A/B rows."""
    config = pipeline_from_source(ConfigSource("<thresholds>", {
        "dataset": {"path": str(dataset)}, "instances": {"conditions": ["a", "b"]},
        "backend": backend, "strategy": "basic", "parser": "official",
        "scorers": ["official", "diagnose"], "cache": False, "output": str(out),
    }, {}))  # fmt: skip
    asyncio.run(PipelineRun(config).run())
    return [{**r.scores["diagnose"], "gt": (r.scores["official"]["gt_u"], r.scores["official"]["gt_v"])}
            for r in iter_rows(out / "results.jsonl") if r.scores.get("diagnose", {}).get("answered")]  # fmt: skip


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset")
    parser.add_argument("--houses", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    dataset = dataset_path(args)
    work = Path(tempfile.mkdtemp(prefix="diagnose_runs_"))
    scores = {name: run_system(dataset, backend, work / name) for name, backend in SYSTEMS.items()}
    print(f"dataset {dataset}; Inferred + Stated answers per system: {len(next(iter(scores.values())))}\n")
    print("anchor_distance (normalized): percentiles, then share of answers beyond each candidate threshold")
    print(f"{'system':<10} {'p50':>6} {'p90':>6} {'p99':>6} {'max':>6}  " + "  ".join(f">{t:.2f}" for t in ANCHOR_CANDIDATES))
    for name, rows in scores.items():
        d = np.array([r["anchor_distance"] for r in rows])
        p50, p90, p99 = np.percentile(d, [50, 90, 99])
        beyond = "  ".join(f"{np.mean(d > t):5.1%}" for t in ANCHOR_CANDIDATES)
        print(f"{name:<10} {p50:6.3f} {p90:6.3f} {p99:6.3f} {d.max():6.3f}  {beyond}")
    print("\negocentric-bias margin on planted-0 (every answer is the ground truth + 5 px noise):")
    print(f"{'margin':>7} {'eligible':>9} {'wrong votes':>12}")
    rows = scores["planted-0"]
    for margin in MARGIN_CANDIDATES:
        eligible = [r for r in rows if math.dist(r["egocentric"], [min(1, max(0, g)) for g in r["gt"]]) > margin]
        wrong = sum(1 for r in eligible if r["l2_egocentric"] < r["l2_truth"])
        print(f"{margin:7.2f} {len(eligible):9d} {wrong:12d}")
    mirror_check(dataset)
    return 0


def mirror_check(root: Path) -> None:
    """How often the relation region of a left/right instance contains the mirrored target, by
    how far apart the two are in the frame: the observer view, and exploration frames that show
    the anchor with both targets in front of the camera."""
    from povagent.dataset.loader import load_dataset, placement_case
    from povagent.geometry.counterfactual import mirrored_target
    from povagent.geometry.relation_region import region_in_frame, valid_placements
    from povagent.scoring.diagnosis import official_uv

    dataset = load_dataset(root, check_images=False)
    bins = ((0.0, 0.05), (0.05, 0.1), (0.1, 0.2), (0.2, 0.3), (0.3, 2.0))
    counts: dict[tuple[str, int], list[int]] = {}
    for inst in dataset.instances(conditions=["a", "c"], directions=["left", "right"]):
        case = placement_case(dataset.houses[inst.house_id].pairs[inst.pair_id], inst.direction)
        placements, mirror = valid_placements(case), mirrored_target(case)
        for frame in inst.frames:
            if inst.condition == "a" and str(inst.anchor_object.objectId) not in frame.in_frame_hits:
                continue
            if frame.camera.project_point(mirror)[2] <= 1e-6 or frame.camera.project_point(inst.target)[2] <= 1e-6:
                continue
            truth, m = official_uv(np.asarray(inst.target), frame), official_uv(mirror, frame)
            k = next(i for i, (lo, hi) in enumerate(bins) if lo <= math.dist(truth, m) < hi)
            cell = counts.setdefault((str(inst.condition), k), [0, 0])
            cell[0] += 1
            cell[1] += region_in_frame(placements, frame.camera).contains(m[0] * frame.camera.width, m[1] * frame.camera.height)
    print("\nrelation region vs the mirrored target (left/right), by their distance in the frame:")
    print(f"{'frames':<22} " + " ".join(f"{f'{lo:.2f}-{hi:.2f}':>11}" for lo, hi in bins))
    for cond, label in (("c", "observer view (C)"), ("a", "exploration (A)")):
        cells = [counts.get((cond, k), [0, 0]) for k in range(len(bins))]
        print(f"{label:<22} " + " ".join(f"{f'{c[1]}/{c[0]}':>11}" for c in cells) + "   (contained / frames)")


if __name__ == "__main__":
    sys.exit(main())
