"""What a rendered view costs beside the Embree casts it is made of (issue 44, item 3).

    python benchmarks/bench_render_view.py [--rounds 3] [--views 20]

House 0 (seed 0) is built once; ``--views`` of its exploration cameras are rendered. For each
camera, in one process and interleaved camera by camera (the machine is shared), the CPU time
(``time.process_time``) and minor page faults of:

* ``primary``: the bare Embree cast of the view's 512x512 primary rays (the renderer's own
  scene, rays and origin, nothing else);
* ``shadow``: the Embree occlusion pass of the same view's shadow rays, as the renderer casts
  it (the rays are made beforehand, outside the clock);
* ``view``: a whole view as the active mode makes it (:meth:`ActiveHouse.render_png`: render,
  shade and encode the PNG as the writer does);
* ``render``: the same view's colours without the PNG encoding (:meth:`Renderer.render_planes`),
  so the split between shading and encoding shows (the encoding is ``generate/frame_png.py``:
  Pillow's row filters, then zlib with Pillow's settings, for Pillow's bytes; zlib's share is
  fixed by the byte-exact PNGs);
* ``numpy``: the same view on numpy's path (every module's compiled loop switched off, as an
  install without a C compiler runs), so the compiled loops' gain is measured in the same run;
  its PNG must be the same bytes as ``view``'s (checked once per camera).

The four take turns in a rotating order (camera by camera, round by round), so none always
runs first on a cold cache or right after another. The machine is shared: CPU time
(``time.process_time``) leaves out the time other jobs hold the cores, but their cache and
memory traffic still slows numpy's passes more than Embree's casts, so the load average is
printed before and after every round. Prints per round the mean of each and the figure: view /
(primary + shadow), goal <= 1.5 (issue 55 goal 4; the issue counts the encoding in the view's cost), beside
render / (primary + shadow); the median over rounds goes to
``benchmarks/results/bench_render_view.json``.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import resource
import statistics
import threading
import time
from pathlib import Path

import numpy as np
from results_file import figure, record


def shadow_rays(renderer, camera) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shadow pass's (starts, directions, lengths) of ``camera``'s view, as ``render`` makes them."""
    from povagent.generate.mesh_parts import CEILING, EMISSIVE

    d = renderer._directions(camera)
    origin = np.asarray(camera.position, dtype=np.float32)
    out = renderer._scene.run(np.broadcast_to(origin, d.T.shape), d.T, output=1)
    tri = out["primID"].astype(np.intp)
    hit = tri >= 0
    idx = np.flatnonzero(hit)
    tri, dh = tri[idx], d[:, idx]
    p = dh * out["tfar"][idx]
    p += origin[:, None]
    n, L = np.take(renderer._normals, tri, axis=1), np.take(renderer._lights, tri, axis=1)
    facing = (n * dh).sum(axis=0)
    np.negative(n, out=n, where=facing > 0)
    L -= p
    dist = np.sqrt((L * L).sum(axis=0))
    L /= dist
    lambert = (n * L).sum(axis=0)
    mat = np.take(renderer._materials, tri)
    probe = (lambert > 0.02) & (mat != EMISSIVE) & (mat != CEILING)
    start = n * np.float32(2e-3)
    start += p
    length = dist - np.float32(0.05)
    length[~probe] = -1.0
    return np.ascontiguousarray(start.T), np.ascontiguousarray(L.T), length


#: The modules with a compiled loop (``_COMPILED``: the loop, or ``None`` for numpy's path).
LOOP_MODULES = ("povagent.generate.frame_png", "povagent.generate.renderer", "povagent.generate.visible_face")


@contextlib.contextmanager
def numpy_path():
    """Every compiled loop switched off for the block (numpy's path, the same bytes)."""
    modules = [importlib.import_module(name) for name in LOOP_MODULES]
    kept = [(m, m._COMPILED) for m in modules if hasattr(m, "_COMPILED")]
    for m, _ in kept:
        m._COMPILED = None
    try:
        yield
    finally:
        for m, loop in kept:
            m._COMPILED = loop


def on_numpy_path(fn):
    def run():
        with numpy_path():
            return fn()

    return run


def timed(fn) -> tuple[float, int]:
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    t = time.process_time()
    fn()
    return time.process_time() - t, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--views", type=int, default=20)
    args = parser.parse_args()
    from povagent.active.house import ActiveHouse
    from povagent.generate.exploration import plan_tour
    from povagent.generate.house_pipeline import build_house

    built = build_house(0, 0)
    renderer = built.renderer
    house = ActiveHouse(Path("."), "train_house_00000", 0, 0, built, threading.Lock())
    cameras = plan_tour(built.house, renderer, args.views)
    house.render_png(cameras[0])  # the ray grid of the frame size is built once
    from povagent.generate.compiled_loops import built_loops

    loops = built_loops()
    print(f"compiled loops built: {loops}")
    for camera in cameras:  # the two paths' bytes, before any timing
        with numpy_path():
            reference = house.render_png(camera)
        assert house.render_png(camera) == reference, "the compiled loops changed a view's bytes"
    rays = [shadow_rays(renderer, c) for c in cameras]
    print(f"load before: {os.getloadavg()}")
    per_round: dict[str, list[float]] = {"primary": [], "shadow": [], "view": [], "render": [], "numpy": [], "ratio": [], "render_ratio": [], "numpy_ratio": []}
    faults: dict[str, list[int]] = {"primary": [], "shadow": [], "view": [], "render": [], "numpy": []}
    for r in range(args.rounds):
        cpu: dict[str, list[float]] = {"primary": [], "shadow": [], "view": [], "render": [], "numpy": []}
        load_before = os.getloadavg()[0]
        for k, (camera, (start, direction, length)) in enumerate(zip(cameras, rays)):
            d = renderer._directions(camera).T
            origins = np.broadcast_to(np.asarray(camera.position, dtype=np.float32), d.shape)
            # the lambdas are timed within this iteration: they see this camera's values
            contenders = [
                ("primary", lambda: renderer._scene.run(origins, d, output=1)),  # noqa: B023
                ("shadow", lambda: renderer._shadow_scene.run(start, direction, dists=length, query="OCCLUDED")),  # noqa: B023
                ("view", lambda: house.render_png(camera)),  # noqa: B023
                ("render", lambda: renderer.render_planes(camera)),  # noqa: B023
                ("numpy", on_numpy_path(lambda: house.render_png(camera))),  # noqa: B023
            ]
            turn = (k + r) % len(contenders)
            for name, fn in contenders[turn:] + contenders[:turn]:
                seconds, flt = timed(fn)
                cpu[name].append(seconds)
                faults[name].append(flt)
        means = {k: statistics.mean(v) for k, v in cpu.items()}
        for k, v in means.items():
            per_round[k].append(v)
        per_round["ratio"].append(means["view"] / (means["primary"] + means["shadow"]))
        per_round["render_ratio"].append(means["render"] / (means["primary"] + means["shadow"]))
        per_round["numpy_ratio"].append(means["numpy"] / means["view"])
        print(f"round {r + 1}: primary {1000 * means['primary']:.1f} ms, shadow {1000 * means['shadow']:.1f} ms, "
              f"view {1000 * means['view']:.1f} ms CPU: view / (primary + shadow) = {per_round['ratio'][-1]:.2f}; "
              f"without the PNG {1000 * means['render']:.1f} ms = {per_round['render_ratio'][-1]:.2f}; "
              f"numpy's path {1000 * means['numpy']:.1f} ms = {per_round['numpy_ratio'][-1]:.2f}x the view; "
              f"page faults per view {statistics.mean(faults['view'][-len(cameras):]):.0f}; "
              f"load {load_before:.2f} -> {os.getloadavg()[0]:.2f}", flush=True)
    ratio, render_ratio = statistics.median(per_round["ratio"]), statistics.median(per_round["render_ratio"])
    numpy_ratio = statistics.median(per_round["numpy_ratio"])
    med = {k: 1000 * statistics.median(v) for k, v in per_round.items() if not k.endswith("ratio")}
    load = os.getloadavg()
    print(f"median: view {med['view']:.1f} ms = {ratio:.2f}x primary + shadow ({med['primary']:.1f} + {med['shadow']:.1f} ms); "
          f"without the PNG {med['render']:.1f} ms = {render_ratio:.2f}x; numpy's path {med['numpy']:.1f} ms = {numpy_ratio:.2f}x the view; "
          f"{statistics.mean(faults['view']):.0f} page faults per view; load after: {load}")
    setting = f"house 0 (seed 0), {len(cameras)} exploration cameras, 512x512; CPU time, median of {args.rounds} interleaved rounds"
    record("bench_render_view", [
        figure("rendered view / (primary rays + shadow pass)", round(ratio, 2), "x", target="<= 1.5", comparison=setting),
        figure("rendered view (render, shade, PNG)", round(med["view"], 1), "ms", comparison="ActiveHouse.render_png"),
        figure("view without the PNG encoding / (primary rays + shadow pass)", round(render_ratio, 2), "x",
               comparison="Renderer.render_planes, same cameras and rounds"),
        figure("view without the PNG encoding", round(med["render"], 1), "ms", comparison="Renderer.render_planes"),
        figure("view on numpy's path (no compiled loop) / view", round(numpy_ratio, 2), "x",
               comparison=f"the same cameras and rounds, the same PNG bytes; compiled loops built: {', '.join(k for k, v in loops.items() if v) or 'none'}"),
        figure("view on numpy's path", round(med["numpy"], 1), "ms"),
        figure("primary rays, bare Embree cast", round(med["primary"], 1), "ms"),
        figure("shadow pass, bare Embree cast", round(med["shadow"], 1), "ms"),
        figure("page faults per view", round(statistics.mean(faults["view"])), "count"),
    ], note=("the PNG is encoded by generate/frame_png.py (Pillow's bytes: the row filters chosen with numpy, "
             "zlib at level 1 with Pillow's settings, zlib's share fixed by the byte-exact PNGs); the load slows "
             "numpy's shading and filter passes more than Embree's casts, so the ratio rises with the load average"))


if __name__ == "__main__":
    main()
