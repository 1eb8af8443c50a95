"""Do exported rationales teach the right thing? Two checks over every exported example.

1. The final answers, read back by the *official* parser and scored by the official scorer:
   with ``--exact-answers`` the mean L2 must be 0 (they are the ground truth); with whole
   pixels it is bounded by the rounding (at most 0.5 px on each axis).
2. The ``geometric`` strategy's solver, fed what the S-CoT rationale's text states, places the
   target; its pixel in the stated frame is compared with the rationale's answer (median, p90,
   share within 2 px, per direction). The text is read back, numbers as written (whole pixels,
   centimetres): the anchor's centre and box in the stated frame and in the other views named
   (step 3), the surface (step 4d), and either where the speaker stood (step 2, metres from the
   stated frame's camera: ``speaker_at``) or, as a model's answer would be used, the pixel of the
   observer's furniture (the solver locates it from that one view at its type's usual height).
   The furniture, anchor and direction words the solver reads from the sentence are the facts'.

``--profile`` adds where the residual comes from: the same placement with one input at a time
replaced by the scene's truth (the anchor's centre, its extent, where the speaker stood), with
every input exact, with unrounded pixels, and with the observer's furniture (its true centre, or
as located from its stated pixel) standing for the speaker; and counts the misses by kind (an
anchor seen in one view only, an anchor box cut by the image border).

Usage: python benchmarks/rationale_consistency.py [--houses 10] [--seed 0] [--dataset DIR] [--profile]
(generates the houses when no dataset is given; about 10 s a house on one core).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import re
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from povagent.dataset.loader import load_dataset, placement_case
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Response
from povagent.geometry.placement import AnchorEstimate, place_target, surface_kind
from povagent.geometry.size_priors import size_prior
from povagent.geometry.triangulation import Sighting, locate
from povagent.plugins import get_plugin_host
from povagent.scoring.normalized_l2 import score_point
from povagent.tasks.scene_facts import PixelBox
from povagent.train.examples import house_examples, make_strategy
from povagent_plugins.strategies.geometric import Detection, parse_detections

SPAN = r", spanning x (\d+)-(\d+) and y (\d+)-(\d+)"
VIEW = re.compile(r"Image (\d+) near \((-?\d+), (-?\d+)\)(?:" + SPAN + ")?")
STOOD = re.compile(r"stood (\d+\.\d+) m to the (left|right) of the camera and (\d+\.\d+) m (ahead of|behind) it")
DIRECTIONS = ("left", "right", "front", "up")


@dataclass(frozen=True)
class Stated:
    """What one S-CoT rationale's text states, as written."""

    frame: int
    anchor: Detection
    other_views: tuple[Detection, ...]
    furniture_xy: tuple[float, float] | None
    stood: tuple[float, float]  # metres to the camera's right, along its heading
    surface: str
    answer: tuple[float, float]


def _box(groups: tuple[str | None, ...]) -> tuple[float, float, float, float] | None:
    if groups[0] is None:
        return None
    x0, x1, y0, y1 = (float(v) for v in groups)  # type: ignore[arg-type]
    return (x0, y0, x1, y1)


def read_rationale(text: str) -> Stated:
    """The numbers an S-CoT rationale states, read from its text."""
    answer = json.loads(text.splitlines()[-1])
    k = int(answer["selected_image"])
    step2 = text.split("Step 2")[1].split("Step 3")[0]
    step3 = text.split("Step 3")[1].split("Step 4")[0]
    here, _, others = step3.partition("Image ")
    centre = re.search(r"\((-?\d+), (-?\d+)\)", here)
    assert centre is not None, step3
    span = re.search(SPAN, here)
    anchor = Detection(k, (float(centre[1]), float(centre[2])), _box(span.groups()) if span else None)
    views = tuple(Detection(int(m[1]), (float(m[2]), float(m[3])), _box(m.groups()[3:])) for m in VIEW.finditer("Image " + others)) if others else ()
    furniture = re.search(r"\((-?\d+), (-?\d+)\)", step2)  # the one pixel step 2 states: the furniture's
    stood = STOOD.search(step2)
    assert stood is not None, step2
    right = float(stood[1]) * (1 if stood[2] == "right" else -1)
    ahead = float(stood[3]) * (1 if stood[4] == "ahead of" else -1)
    surface = re.search(r"relative to the [^(]*\(([^)]*)\)\.", text)
    assert surface is not None, text
    return Stated(
        k,
        anchor,
        views,
        (float(furniture[1]), float(furniture[2])) if furniture else None,
        (right, ahead),
        surface[1],
        (float(answer["x"]), float(answer["y"])),
    )


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


def _distance(inst, k: int, target, answer: tuple[float, float]) -> float:  # type: ignore[no-untyped-def]
    """Pixel distance in frame ``k`` between ``target`` (3D) and the stated answer."""
    if target is None:
        return math.inf
    u, v, depth = inst.frames[k].camera.project_point(target)
    if not depth > 0:
        return math.inf
    w, h = inst.frame_size
    return math.hypot(u * w - answer[0], v * h - answer[1])


def solver_from_text(ds, examples, speaker: bool) -> list[tuple[str, float]]:  # type: ignore[no-untyped-def]
    """(direction, pixel distance) per A/B example: the geometric strategy's solve, its
    sub-questions answered with what the rationale states; ``speaker``: where the speaker
    stood is passed as ``speaker_at`` (else the furniture is located from its stated pixel)."""
    solver = get_plugin_host().create("strategy", "geometric", {})
    out = []
    for ex in examples:
        if ex.facts.frame_index is None:
            continue
        inst, f, s = ds.instance(ex.id), ex.facts, read_rationale(ex.answer)

        async def ask(request, f=f, s=s):  # type: ignore[no-untyped-def]
            q = request.question or {}
            if q.get("kind") == "read":
                doc = {"observer": f.observer_type, "anchor": f.anchor_type, "direction": f.direction.value}
            elif q.get("kind") == "surface":
                doc = {"surface": surface_kind(s.surface, f.anchor_type)}
            elif q.get("role") == "anchor":
                doc = anchor_answer(s)
            else:
                doc = {"detections": [{"image": s.frame, "x": s.furniture_xy[0], "y": s.furniture_xy[1]}] if s.furniture_xy else []}
            return Response(text=json.dumps(doc))

        stood = inst.frames[s.frame].camera.floor_point(*s.stood) if speaker else None
        turns = asyncio.run(solver.solve(inst, ask, ImageStore(), speaker_at=stood))
        out.append((f.direction.value, _distance(inst, s.frame, turns[-1][1].solved_point, s.answer)))
    return out


def anchor_answer(s: Stated) -> dict[str, object]:
    """The anchor's detections as a model would answer the solver's locate question."""
    detections = []
    for d in (s.anchor, *s.other_views):
        doc: dict[str, object] = {"image": d.frame, "x": d.pixel[0], "y": d.pixel[1]}
        if d.box is not None:
            doc["box"] = list(d.box)
        detections.append(doc)
    return {"detections": detections}


def _pixel_box(b: PixelBox | None) -> tuple[float, float, float, float] | None:
    return None if b is None else (b.x0, b.y0, b.x1, b.y1)


def profile(ds, examples) -> dict[str, list[tuple[str, float]]]:  # type: ignore[no-untyped-def]
    """The solver's placement with inputs replaced by the truth, one at a time (see the docstring)."""
    solver = get_plugin_host().create("strategy", "geometric", {})
    out: dict[str, list[tuple[str, float]]] = {}
    for ex in examples:
        if ex.facts.frame_index is None:
            continue
        inst, f, s = ds.instance(ex.id), ex.facts, read_rationale(ex.answer)
        case = placement_case(ds.houses[inst.house_id].pairs[inst.pair_id], inst.direction)
        cams = [fr.camera for fr in inst.frames]
        w, h = inst.frame_size
        # what the solver makes of the stated detections (pixels clamped into the image)
        stated = solver.anchor_estimate(f.anchor_type, parse_detections(anchor_answer(s), len(cams), w, h)[0], cams)
        unrounded = solver.anchor_estimate(
            f.anchor_type,
            [
                Detection(s.frame, f.anchor_xy, _pixel_box(f.anchor_box)),
                *(Detection(v.frame_index, v.xy, _pixel_box(v.box)) for v in f.anchor_other_views),
            ],
            cams,
        )
        true_centre = np.asarray(case.anchor_centre)
        true_half = np.array([case.box.half_xz[0], case.box.top - true_centre[1], case.box.half_xz[1]])
        stood = cams[s.frame].floor_point(*s.stood)
        speaker = np.asarray(case.observer_position)
        furniture_centre = np.asarray(inst.observer_object.raw_metadata.axisAlignedBoundingBox.center.as_tuple())
        # the furniture as the solver locates it from the stated pixel (one view: the ray meets
        # its type's usual centre height), or its fallback when the furniture is not in the frame
        seen = parse_detections(
            {"detections": [{"image": s.frame, "x": s.furniture_xy[0], "y": s.furniture_xy[1]}] if s.furniture_xy else []}, len(cams), w, h
        )[0]
        found = locate([Sighting(cams[d.frame], d.pixel) for d in seen], size_prior(f.observer_type).centre_height)
        located = np.asarray(found.point) if found else np.mean([cams[d.frame].position for d in (s.anchor, *s.other_views)], axis=0)
        out.setdefault("furniture located, metres off its centre", []).append((f.direction.value, float(np.hypot(*(located - furniture_centre)[[0, 2]]))))
        inputs = {
            "as stated": (stated.centre, stated.half, stood),
            "anchor centre true": (true_centre, stated.half, stood),
            "anchor extent true": (stated.centre, true_half, stood),
            "anchor box true": (true_centre, true_half, stood),
            "every input true": (true_centre, true_half, speaker),
            "every input unrounded": (unrounded.centre, unrounded.half, speaker),
            "anchor box true, the furniture's true centre for the speaker": (true_centre, true_half, furniture_centre),
            "anchor box true, the furniture located from its pixel for the speaker": (true_centre, true_half, located),
            "anchor as stated, the furniture located from its pixel for the speaker": (stated.centre, stated.half, located),
        }
        kind = surface_kind(s.surface, f.anchor_type)
        for name, (centre, half, observer) in inputs.items():
            anchor = AnchorEstimate(tuple(centre), tuple(half))  # type: ignore[arg-type]
            target = place_target(f.direction.value, anchor, f.anchor_type, observer, kind)
            out.setdefault(name, []).append((f.direction.value, _distance(inst, s.frame, target, s.answer)))
        cut = s.anchor.box is not None and (min(s.anchor.box) <= 1 or max(s.anchor.box) >= min(w, h) - 2)
        out.setdefault("kind", []).append(("one view" if not s.other_views else "box cut by the border" if cut else "other", 0.0))
    return out


def summary(pairs: list[tuple[str, float]]) -> str:
    """Median, p90 and share within 2 px, overall and per direction."""
    parts = []
    for name in ("all", *DIRECTIONS):
        dist = [d for direction, d in pairs if name in ("all", direction)]
        if not dist:
            continue
        finite = sorted(d for d in dist if math.isfinite(d))
        p90 = finite[int(0.9 * (len(finite) - 1))] if finite else math.nan
        within = sum(1 for d in dist if d <= 2.0) / len(dist)
        parts.append(f"{name} (n {len(dist)}): median {statistics.median(finite):.2f} px, p90 {p90:.2f} px, within 2 px {within:.1%}")
    return "\n  ".join(parts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--houses", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dataset", type=Path)
    ap.add_argument("--profile", action="store_true", help="where the solver's residual comes from")
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
        if rationale != "s-cot":
            continue
        print("geometric solver from the stated facts, where the speaker stood given (speaker_at), pixel distance to the answer:\n  "
              + summary(solver_from_text(ds, examples, speaker=True)))
        print("geometric solver from the stated facts, the furniture located from its stated pixel instead:\n  "
              + summary(solver_from_text(ds, examples, speaker=False)))
        if args.profile:
            rows = profile(ds, examples)
            kinds = [k for k, _ in rows.pop("kind")]
            off = [d for _, d in rows.pop("furniture located, metres off its centre")]
            print(
                f"profile, the furniture located from its stated pixel: {statistics.median(off):.2f} m off its centre (median), p90 "
                f"{sorted(off)[int(0.9 * (len(off) - 1))]:.2f} m"
            )
            for name, pairs in rows.items():
                print(f"profile, {name}:\n  " + summary(pairs))
            misses: dict[str, list[float]] = {k: [] for k in sorted(set(kinds))}
            for kind, (_, d) in zip(kinds, rows["as stated"]):
                if not d <= 2.0:
                    misses[kind].append(d)
            print("profile, misses of 'as stated' by kind: " + ", ".join(
                f"{k} {len(m)} of {kinds.count(k)}" + (f" (median {statistics.median(m):.1f} px, max {max(m):.1f})" if m else "") for k, m in misses.items()
            ))
    return 0


if __name__ == "__main__":
    sys.exit(main())
