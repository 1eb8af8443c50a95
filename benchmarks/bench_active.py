"""Benchmark of the active mode: render cost, house rebuild amortised, episode throughput, oracle L2.

Run: ``python benchmarks/bench_active.py --data DIR [--houses 47] [--episodes-per-house 3]
[--oracle-houses 10]``. ``DIR`` is a dataset made by ``povagent generate`` (made here with
``--seed 0 --frames 30 --jobs 2`` when it does not exist; 47 houses take minutes). Prints, from
measurements in this run:

* CPU ms per rendered view (512x512 PNG, as the active mode stores it; goal: <= 100 ms), over
  the cameras of a house's exploration frames turned by 15 degrees;
* the CPU of one house rebuild, and its share of an 8-action episode's CPU once the house is
  cached (the second episode of a house on finds it in the per-process cache; goal: < 5%), and
  spread over the house's episodes in the throughput run;
* episode throughput with ``explorer-random`` (8 actions) over every house, a sample of
  ``--episodes-per-house`` episodes a house (one run a house, the dataset loaded once):
  episodes per wall-clock second and CPU per episode;
* ``explorer-oracle``'s official L2 mean per condition (Inferred, Stated, Given) over every
  instance of the first ``--oracle-houses`` houses (goal: <= 0.01).

CPU is ``time.process_time`` (the machine may be shared); figures go to
``benchmarks/results/bench_active.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import yaml
from results_file import record


def ensure_dataset(data: Path, houses: int) -> int:
    """Generate the dataset unless it exists; returns the number of houses in it."""
    from povagent.generate import generate_dataset

    if not (data / "meta.json").is_file():
        print(f"generating {houses} houses into {data} (seed 0, 30 frames, 2 jobs) ...", flush=True)
        generate_dataset(data, houses=houses, seed=0, frames=30, jobs=2, progress=False)
    return int(json.loads((data / "meta.json").read_text())["counts"]["houses"])


def render_cost(data: Path) -> dict:
    """CPU of one rebuild, of a view, of a cached lookup, on house 0."""
    from povagent.active.house import forget_houses, house_for
    from povagent.active.pose import Pose

    forget_houses()
    t = time.process_time()
    house = house_for(data, "train_house_00000")
    rebuild = time.process_time() - t
    log = json.loads((data / "artifacts" / "train_house_00000" / "exploration_log.json").read_text())
    poses = [Pose(*e["camera"]["cam_pos"], e["camera"]["cam_yaw"] + 15.0, e["camera"]["cam_horizon"]) for e in log]
    house.render_png(poses[0].camera())  # the ray grid of the frame size is built once
    costs = []
    for pose in poses:
        t = time.process_time()
        house.render_png(pose.camera())
        costs.append(time.process_time() - t)
    t = time.process_time()
    for _ in range(100):
        house_for(data, "train_house_00000")
    lookup = (time.process_time() - t) / 100
    return {"rebuild_s": rebuild, "view_s": statistics.mean(costs), "view_max_s": max(costs), "views": len(costs), "lookup_s": lookup}


def run(data: Path, out: Path, backend: str, instances: dict, dataset: object = None) -> tuple[list, float, float]:
    """A pipeline run of the active strategy; returns (rows, wall s, CPU s). ``dataset``: the
    loaded dataset to reuse (else the run loads it)."""
    from povagent.config.pipeline import load_pipeline
    from povagent.results.rows import read_rows
    from povagent.run.runner import run_pipeline

    cfg = out.with_suffix(".yaml")
    cfg.write_text(yaml.safe_dump({"dataset": {"path": str(data)}, "instances": instances, "backend": backend,
                                   "strategy": "active", "parser": "active", "scorers": ["official"],
                                   "concurrency": 2, "output": str(out)}))  # fmt: skip
    config = load_pipeline(cfg)
    w, c = time.perf_counter(), time.process_time()
    run_pipeline(config, dataset=dataset) if dataset is not None else run_pipeline(config)
    return read_rows(out / "results.jsonl"), time.perf_counter() - w, time.process_time() - c


def random_over_every_house(data: Path, out: Path, houses: int, per_house: int) -> tuple[list, float, float]:
    """``explorer-random`` on ``per_house`` sampled instances of every house (one run a house,
    the dataset loaded once); returns (rows, wall s, CPU s) summed over the runs."""
    from povagent.dataset.loader import load_dataset

    dataset = load_dataset(data)
    rows, wall, cpu = [], 0.0, 0.0
    for i in range(houses):
        r, w, c = run(data, out / f"house_{i:05d}", "explorer-random",
                      {"houses": [f"train_house_{i:05d}"], "sample": per_house, "seed": 0}, dataset)  # fmt: skip
        rows += r
        wall += w
        cpu += c
    return rows, wall, cpu


def main() -> None:
    """Measure, print, write the JSON."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, required=True, help="a generated dataset (made here if missing)")
    ap.add_argument("--houses", type=int, default=47, help="houses to generate when --data does not exist")
    ap.add_argument("--episodes-per-house", type=int, default=3, help="explorer-random episodes sampled per house")
    ap.add_argument("--oracle-houses", type=int, default=10, help="houses whose every instance the oracle runs")
    args = ap.parse_args()
    from povagent.active.house import forget_houses
    from povagent.results.episode import read_record

    houses = ensure_dataset(args.data, args.houses)
    print(f"dataset: {args.data} ({houses} houses)", flush=True)
    cost = render_cost(args.data)
    print(f"render: {1000 * cost['view_s']:.1f} ms CPU per view (max {1000 * cost['view_max_s']:.1f}, {cost['views']} views); "
          f"rebuild {cost['rebuild_s']:.2f} s CPU; cached lookup {1e6 * cost['lookup_s']:.1f} us", flush=True)  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench-active-") as tmp:
        forget_houses()
        (Path(tmp) / "random").mkdir()
        rows, wall, cpu = random_over_every_house(args.data, Path(tmp) / "random", houses, args.episodes_per_house)
        records = [read_record(r.exchanges[-1].raw) for r in rows if r.exchanges]
        actions = statistics.mean(r.counts.actions for r in records if r is not None)
        houses_seen = len({r.house_id for r in rows})
        per_episode = cpu / len(rows)
        print(f"explorer-random: {len(rows)} episodes over {houses_seen} houses in {wall:.1f} s wall, {cpu:.1f} s CPU: "
              f"{len(rows) / wall:.2f} episodes/s, {per_episode:.2f} s CPU an episode ({actions:.1f} actions)", flush=True)  # fmt: skip
        episode_8 = 8 * cost["view_s"]  # the render CPU of an 8-action episode (the bulk of its CPU)
        cached_share = cost["lookup_s"] / per_episode
        spread_share = cost["rebuild_s"] * houses_seen / cpu
        print(f"house rebuild: {100 * cached_share:.4f}% of an episode's CPU once cached; "
              f"{100 * spread_share:.1f}% of the random run's CPU ({len(rows) / houses_seen:.1f} episodes a house)", flush=True)  # fmt: skip
        forget_houses()
        oracle_houses = [f"train_house_{i:05d}" for i in range(min(args.oracle_houses, houses))]
        orows, owall, _ = run(args.data, Path(tmp) / "oracle", "explorer-oracle", {"houses": oracle_houses})
        by_cond: dict[str, list[float]] = {}
        for r in orows:
            l2 = r.scores.get("official", {}).get("l2")
            by_cond.setdefault(r.condition, []).append(float(l2) if l2 is not None else float("nan"))
        oracle = {c: statistics.mean(v) for c, v in sorted(by_cond.items())}
        print(f"explorer-oracle over {len(oracle_houses)} houses ({len(orows)} instances, {owall:.1f} s wall): "
              + ", ".join(f"{c}: mean L2 {v:.6f} (max {max(by_cond[c]):.4f}, n={len(by_cond[c])})" for c, v in oracle.items()), flush=True)  # fmt: skip
    names = {"a": "Inferred", "b": "Stated", "c": "Given"}
    figures = [
        {"name": "render CPU per view", "value": round(1000 * cost["view_s"], 2), "unit": "ms", "target": "<= 100 ms",
         "comparison": "mean over the exploration cameras of house 0 turned 15 degrees, 512x512 PNG as stored"},
        {"name": "house rebuild CPU", "value": round(cost["rebuild_s"], 3), "unit": "s", "target": "",
         "comparison": "plan, furnish, mesh and embree scenes of house 0 (once per house per process)"},
        {"name": "house lookup share of an episode once cached", "value": round(100 * cached_share, 5), "unit": "%",
         "target": "< 5%", "comparison": "per-process cache hit CPU vs explorer-random episode CPU (8 actions)"},
        {"name": "house rebuilds share of the random run", "value": round(100 * spread_share, 2), "unit": "%",
         "target": "", "comparison": f"{houses_seen} rebuilds vs the run's CPU, {len(rows) / houses_seen:.1f} episodes a house"},
        {"name": "render CPU of an 8-action episode", "value": round(episode_8, 3), "unit": "s", "target": "",
         "comparison": "8 x render CPU per view"},
        {"name": "explorer-random episodes per second", "value": round(len(rows) / wall, 3), "unit": "episodes/s",
         "target": "", "comparison": f"{len(rows)} episodes over {houses_seen} houses (one run a house), concurrency 2, wall clock"},
        {"name": "explorer-random CPU per episode", "value": round(per_episode, 3), "unit": "s", "target": "",
         "comparison": f"mean {actions:.1f} actions an episode; includes house rebuilds"},
        *[{"name": f"explorer-oracle official L2 mean, {names[c]}", "value": round(v, 6), "unit": "normalized L2",
           "target": "<= 0.01", "comparison": f"every instance of {len(oracle_houses)} houses (n={len(by_cond[c])})"}
          for c, v in oracle.items()],
    ]  # fmt: skip
    command = "python benchmarks/bench_active.py " + " ".join(sys.argv[1:])
    print(f"figures: {record('bench_active', figures, command)}")


if __name__ == "__main__":
    main()
