"""Frames rendered under every embree instruction set this CPU runs: how many pixels differ.

    python benchmarks/bench_render_isa.py [--houses 10] [--frames 30] [--seed 7]

Each instruction set (sse2 ... avx512, as :func:`povagent.testing.embree_isa.cpu_isas` finds)
renders in a child process of its own with embree forced to it (the preloaded shim of
:mod:`povagent.testing.embree_isa`). Every child builds houses 0..N-1 of ``--seed``, plans the
same tour (the cameras are planned in the parent, under the CPU's own kernel, and handed to
every child) and renders each frame; the parent compares colours, depth and instance masks
with the native kernel's, pixel by pixel. Figures: differing pixels per million rendered, per
instruction set; the goal is 0 (``docs/explanation/reproducibility.md`` names what may
still differ). Also the CPU time per frame of the native render, for the cost of deciding
faces exactly.
"""

from __future__ import annotations

import argparse
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from results_file import figure, record

CHILD = r"""
import pickle, sys, time
import numpy as np
from povagent.generate.house_pipeline import build_house
plan = pickle.load(open(sys.argv[1], "rb"))
out = {}
cpu = 0.0
for index, cameras in plan["tours"].items():
    built = build_house(plan["seed"], index)
    for k, camera in enumerate(cameras):
        t0 = time.process_time()
        frame = built.renderer.render(camera)
        cpu += time.process_time() - t0
        out[(index, k)] = (frame.rgb, frame.depth, frame.instance)
pickle.dump({"frames": out, "cpu": cpu}, open(sys.argv[2], "wb"))
"""


def main() -> None:
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house
    from povagent.testing.embree_isa import build_shim, cpu_isas, isa_environment

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--houses", type=int, default=10)
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        tours = {}
        for index in range(args.houses):
            built = build_house(args.seed, index)
            tours[index] = plan_tour(built.house, built.renderer, args.frames)
        (folder / "plan.pkl").write_bytes(pickle.dumps({"seed": args.seed, "tours": tours}))
        shim = build_shim(folder / "shim")
        runs = {"native": {}} | {isa: isa_environment(shim, isa) for isa in cpu_isas()}
        results = {}
        for name, env in runs.items():
            t0 = time.monotonic()
            subprocess.run([sys.executable, "-c", CHILD, str(folder / "plan.pkl"), str(folder / f"{name}.pkl")],
                           env={**os.environ, **env}, check=True)  # fmt: skip
            results[name] = pickle.loads((folder / f"{name}.pkl").read_bytes())
            print(f"{name}: rendered in {time.monotonic() - t0:.0f} s", flush=True)
    native = results["native"]["frames"]
    pixels = sum(rgb.shape[0] * rgb.shape[1] for rgb, _, _ in native.values())
    figures = []
    for name in runs:
        if name == "native":
            continue
        frames = results[name]["frames"]
        rgb = sum(int((frames[k][0] != v[0]).any(axis=2).sum()) for k, v in native.items())
        depth = sum(int((frames[k][1] != v[1]).sum()) for k, v in native.items())
        inst = sum(int((frames[k][2] != v[2]).sum()) for k, v in native.items())
        print(f"embree {name}: {rgb} colour, {depth} depth, {inst} instance pixels differ of {pixels}")
        figures.append(figure(f"pixels whose colour differs from the native kernel's, embree {name}", round(rgb * 1e6 / pixels, 3),
                              "per million", target="0", comparison=f"{len(native)} frames of {args.houses} houses (seed {args.seed})"))  # fmt: skip
        figures.append(figure(f"pixels whose depth or instance differs, embree {name}", round((depth + inst) * 1e6 / pixels, 3), "per million", target="0"))
    per_frame = results["native"]["cpu"] / len(native) * 1000
    figures.append(figure("CPU per rendered 512x512 frame (native kernel)", round(per_frame, 1), "ms"))
    print(f"native: {per_frame:.1f} ms CPU per frame")
    record("bench_render_isa", figures)


if __name__ == "__main__":
    main()
