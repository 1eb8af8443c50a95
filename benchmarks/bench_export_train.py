"""Export throughput and memory: instances/s, MB/s and peak memory at N and 10N houses.

Generates (or reuses) a dataset of --houses-large houses and exports it whole, and a dataset of
its first --houses-small houses (hard links to the same files, in a folder of its own: the
exporter sees a dataset of that size, not a large one cut by a split range), each export in a
fresh process (so peak RSS is the export's own), in the hf, messages and openai formats. Memory
should stay flat in the number of houses: an export plans house by house, writes one shard at a
time and loads one house at a time. An hf shard is cut into at most three row groups (so a
streamed read left early exits: see povagent/train/parquet.py), so its writer buffers a third of
a shard; the hf export is run a second time with the earlier 16 MB row groups
(``MAX_ROW_GROUPS`` lifted) to put the two peaks side by side.

Each line gives the machine's load average (1 min) when the export ended: the figures are
wall-clock on a shared machine. The figures go to benchmarks/results/bench_export_train.json.

Usage: python benchmarks/bench_export_train.py [--houses-small 10] [--houses-large 100]
       [--dataset DIR]   (a generated set with at least --houses-large houses)
       [--formats hf,messages,openai]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from results_file import record

CHILD = r"""
import json, resource, sys, time
from pathlib import Path
import povagent.train.parquet as parquet
from povagent.train.training_export import export_training_set
from povagent.train.export_options import FORMAT_FOLDERS, ExportOptions
root, out, fmt, groups = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3], sys.argv[4]
if groups == "16mb":
    parquet.MAX_ROW_GROUPS = 10**9  # the earlier layout: a row group every 16 MB
t0, c0 = time.perf_counter(), time.process_time()
r = export_training_set(root, out, ExportOptions(format=fmt, split="1,0,0"), check_release=False)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
shards = sorted(p.stat().st_size for p in (out / FORMAT_FOLDERS[fmt][0]).glob("*." + FORMAT_FOLDERS[fmt][1]))
print(json.dumps({"houses": sum(len(v) for v in r.houses_by_split.values()), "examples": r.examples, "wall": wall, "cpu": cpu,
                  "bytes": size, "shards": shards, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def first_houses(root: Path, n: int, into: Path) -> Path:
    """A dataset of ``root``'s first ``n`` houses under ``into``: hard links (copies across devices)."""
    (into / "artifacts").mkdir(parents=True)
    if (root / "meta.json").exists():
        shutil.copy2(root / "meta.json", into / "meta.json")
    houses = sorted(p for p in (root / "artifacts").iterdir() if p.is_dir())[:n]
    for house in houses:
        shutil.copytree(house, into / "artifacts" / house.name, copy_function=_link)
    return into


def _link(src: str, dst: str) -> None:
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def run(root: Path, fmt: str, groups: str = "bounded") -> dict:
    out = Path(tempfile.mkdtemp()) / "export"
    try:
        done = subprocess.run([sys.executable, "-c", CHILD, str(root), str(out), fmt, groups], capture_output=True, text=True, check=True)
        result = json.loads(done.stdout.strip().splitlines()[-1])
        result["load"] = os.getloadavg()[0]
        return result
    finally:
        shutil.rmtree(out.parent, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--houses-small", type=int, default=10)
    ap.add_argument("--houses-large", type=int, default=100)
    ap.add_argument("--dataset", type=Path)
    ap.add_argument("--formats", default="hf,messages,openai")
    args = ap.parse_args(argv)
    root = args.dataset
    if root is None:
        from povagent.generate import generate_dataset

        root = Path(tempfile.mkdtemp()) / "POVBench"
        t = time.perf_counter()
        generate_dataset(root, houses=args.houses_large, seed=0, jobs=2, progress=False)
        print(f"generated {args.houses_large} houses in {time.perf_counter() - t:.0f} s: {root}")
    figures: list[dict] = []
    small_dir = Path(tempfile.mkdtemp())
    try:
        small = first_houses(root, args.houses_small, small_dir / "POVBench")
        runs = [(fmt, "bounded") for fmt in args.formats.split(",")] + ([("hf", "16mb")] if "hf" in args.formats.split(",") else [])
        peaks: dict[tuple[str, str], dict[int, dict]] = {}
        for fmt, groups in runs:
            rows = {args.houses_small: run(small, fmt, groups), args.houses_large: run(root, fmt, groups)}
            peaks[(fmt, groups)] = rows
            label = fmt if groups == "bounded" else f"{fmt} (16 MB row groups)"
            for r in rows.values():
                mb = r["bytes"] / 2**20
                shards = ", ".join(f"{s / 2**20:.0f}" for s in r["shards"])
                print(f"{label:8} {r['houses']:4} houses: {r['examples']:6} examples, {r['examples'] / r['wall']:7.1f} inst/s, "
                      f"{mb / r['wall']:6.1f} MB/s written ({mb:,.0f} MB in {r['wall']:.0f} s, {r['cpu']:.0f} s CPU), "
                      f"peak RSS {r['peak_rss_mb']:.0f} MB, {len(r['shards'])} shard(s) of MB: {shards}; load average {r['load']:.1f}")
                figures += [
                    {"name": f"{label} export, {r['houses']} houses: instances per second", "value": round(r["examples"] / r["wall"], 2),
                     "unit": "instances/s", "target": "", "comparison": f"wall clock on a shared machine (load average {r['load']:.1f})"},
                    {"name": f"{label} export, {r['houses']} houses: peak RSS", "value": round(r["peak_rss_mb"], 1), "unit": "MB",
                     "target": "flat in the number of houses", "comparison": f"{len(r['shards'])} shard(s), default --max-shard-mb 500"},
                ]
            low, high = rows[args.houses_small], rows[args.houses_large]
            ratio = high["peak_rss_mb"] / low["peak_rss_mb"]
            print(f"{label:8} peak memory {high['houses']} vs {low['houses']} houses: x{ratio:.2f}")
            figures.append({"name": f"{label} peak memory, {high['houses']} vs {low['houses']} houses", "value": round(ratio, 3), "unit": "ratio",
                            "target": "about 1 (flat)", "comparison": f"the same export of the first {low['houses']} houses"})
        if ("hf", "16mb") in peaks:
            for houses in (args.houses_small, args.houses_large):
                bounded, old = peaks[("hf", "bounded")][houses], peaks[("hf", "16mb")][houses]
                ratio = bounded["peak_rss_mb"] / old["peak_rss_mb"]
                print(f"hf       {bounded['houses']} houses: peak memory with at most 3 row groups per shard vs 16 MB row groups: x{ratio:.2f}")
                figures.append({"name": f"hf peak memory, at most 3 row groups vs 16 MB row groups, {bounded['houses']} houses", "value": round(ratio, 3),
                                "unit": "ratio", "target": "", "comparison": "the same export with MAX_ROW_GROUPS lifted (a row group every 16 MB)"})
    finally:
        shutil.rmtree(small_dir, ignore_errors=True)
    record("bench_export_train", figures, "python benchmarks/bench_export_train.py " + " ".join(argv if argv is not None else sys.argv[1:]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
