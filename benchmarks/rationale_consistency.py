"""Do exported rationales teach the right thing? Two checks over every exported example.

1. The final answers, read back by the *official* parser and scored by the official scorer:
   with ``--exact-answers`` the mean L2 must be 0 (they are the ground truth); with whole
   pixels it is bounded by the rounding (at most 0.5 px on each axis).
2. The ``geometric`` strategy's solver, fed only what the S-CoT rationale states (the observer's
   furniture, the anchor and the direction; the surface; the anchor's centre and box and the
   furniture's pixel in the stated frame), places the target; its pixel in the stated frame is
   compared with the rationale's answer. One view fixes the anchor's depth only through its
   type's usual size (the solver's prior), so this measures how much the stated facts determine
   the answer, not an exact identity.

Usage: python benchmarks/rationale_consistency.py [--houses 10] [--seed 0] [--dataset DIR]
(generates the houses when no dataset is given; about 10 s a house on one core).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

from povagent.dataset.loader import load_dataset
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Response
from povagent.geometry.placement import surface_kind
from povagent.plugins import get_plugin_host
from povagent.scoring.official import score_point
from povagent.train.examples import house_examples, make_strategy


def official_answers(ds, examples) -> dict[str, float]:  # type: ignore[no-untyped-def]
    """Mean official L2 of the examples' answers, read by the official parser."""
    host = get_plugin_host()
    parser = host.create("parser", "official", {})
    strategy = make_strategy("none")
    l2s, unanswered = [], 0
    for ex in examples:
        inst = ds.instance(ex.id)
        parsed = parser.parse(ex.answer, strategy.answer_spec(inst))
        if not parsed.answered:
            unanswered += 1
            continue
        frame = inst.frames[parsed.selected_image] if inst.condition.uses_exploration_frames else inst.frames[0]
        l2s.append(score_point(inst, frame, parsed.x, parsed.y).l2)
    return {"n": len(l2s), "unanswered": unanswered, "mean_l2": statistics.fmean(l2s), "max_l2": max(l2s)}


def solver_agreement(ds, examples) -> list[float]:  # type: ignore[no-untyped-def]
    """Pixel distance between the solver's target (from the stated facts) and the rationale's answer."""
    solver = get_plugin_host().create("strategy", "geometric", {})
    out = []
    for ex in examples:
        inst = ds.instance(ex.id)
        f = ex.facts
        if f.frame_index is None:
            continue
        k = f.frame_index

        async def ask(request, f=f, k=k):  # type: ignore[no-untyped-def]
            q = request.question or {}
            if q.get("kind") == "read":
                doc = {"observer": f.observer_type, "anchor": f.anchor_type, "direction": f.direction.value}
            elif q.get("kind") == "surface":
                doc = {"surface": surface_kind(f.surface, f.anchor_type)}
            elif q.get("role") == "anchor":
                box = f.anchor_box
                det = {"image": k, "x": f.anchor_xy[0], "y": f.anchor_xy[1]}
                if box is not None:
                    det["box"] = [box.x0, box.y0, box.x1, box.y1]
                doc = {"detections": [det, *({"image": i, "x": p[0], "y": p[1]} for i, p in f.anchor_other_views)]}
            else:
                seen = f.observer_visible and f.observer_xy is not None
                doc = {"detections": [{"image": k, "x": f.observer_xy[0], "y": f.observer_xy[1]}] if seen else []}
            return Response(text=json.dumps(doc))

        turns = asyncio.run(solver.solve(inst, ask, ImageStore()))
        target = turns[-1][1].solved_point
        if target is None:
            continue
        u, v, depth = inst.frames[k].camera.project_point(target)
        if not depth > 0:
            out.append(math.inf)
            continue
        w, h = inst.frame_size
        ax, ay = f.answer_xy
        out.append(math.hypot(u * w - ax, v * h - ay))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--houses", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dataset", type=Path)
    args = ap.parse_args(argv)
    root = args.dataset
    if root is None:
        from povagent.generate import generate_dataset

        root = Path(tempfile.mkdtemp()) / "POVBench"
        t = time.perf_counter()
        generate_dataset(root, houses=args.houses, seed=args.seed, jobs=2, progress=False)
        print(f"generated {args.houses} houses (seed {args.seed}) in {time.perf_counter() - t:.0f} s: {root}")
    ds = load_dataset(root)
    for rationale, exact in (("s-cot", False), ("none", True)):
        strategy = make_strategy(rationale)
        examples, skipped = [], 0
        for house in ds.houses.values():
            for ex in house_examples(house, ds.instances(houses=[house.house_id]), rationale, strategy, seed=0, exact=exact):
                if isinstance(ex, tuple):
                    skipped += 1
                else:
                    examples.append(ex)
        stats = official_answers(ds, examples)
        label = f"{rationale}, {'exact' if exact else 'whole-pixel'} answers"
        print(f"{label}: {stats['n']} answers read by the official parser ({stats['unanswered']} unanswered, "
              f"{skipped} instances no frame can teach): official mean L2 {stats['mean_l2']:.2e}, max {stats['max_l2']:.2e}")
        if rationale == "s-cot":
            dist = solver_agreement(ds, examples)
            finite = sorted(d for d in dist if math.isfinite(d))
            within = sum(1 for d in dist if d <= 2.0)
            p90 = finite[int(0.9 * (len(finite) - 1))] if finite else math.nan
            print(f"geometric solver from the stated facts vs the rationale's answer ({len(dist)} A/B answers): "
                  f"median {statistics.median(finite):.2f} px, p90 {p90:.2f} px, within 2 px {within / len(dist):.1%}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
