"""Export throughput and memory: instances/s, MB/s and peak memory at N and 10N houses.

Generates (or reuses) a dataset of --houses-large houses and exports it whole, and a dataset of
its first --houses-small houses (hard links to the same files, in a folder of its own: the
exporter sees a dataset of that size, not a large one cut by a split range), each export in a
fresh process (so peak RSS is the export's own), in the hf and messages formats. Memory should
stay flat in the number of houses: an export plans house by house, writes one shard at a time,
loads one house at a time and buffers a row group of at most 16 MB.

Each line gives the machine's load average (1 min) when the export ended: the figures are
wall-clock on a shared machine.

Usage: python benchmarks/bench_export_train.py [--houses-small 10] [--houses-large 100]
       [--dataset DIR]   (a generated set with at least --houses-large houses)
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

CHILD = r"""
import json, resource, sys, time
from pathlib import Path
from povagent.train.export import export_training_set
from povagent.train.export_options import ExportOptions
root, out, fmt = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3]
t0, c0 = time.perf_counter(), time.process_time()
r = export_training_set(root, out, ExportOptions(format=fmt, split="1,0,0"), check_release=False)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
shards = sorted(p.stat().st_size for p in (out / ("data" if fmt == "hf" else "messages")).glob("*") if p.is_file())
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


def run(root: Path, fmt: str) -> dict:
    out = Path(tempfile.mkdtemp()) / "export"
    try:
        done = subprocess.run([sys.executable, "-c", CHILD, str(root), str(out), fmt], capture_output=True, text=True, check=True)
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
    ap.add_argument("--formats", default="hf,messages")
    args = ap.parse_args(argv)
    root = args.dataset
    if root is None:
        from povagent.generate import generate_dataset

        root = Path(tempfile.mkdtemp()) / "POVBench"
        t = time.perf_counter()
        generate_dataset(root, houses=args.houses_large, seed=0, jobs=2, progress=False)
        print(f"generated {args.houses_large} houses in {time.perf_counter() - t:.0f} s: {root}")
    small_dir = Path(tempfile.mkdtemp())
    try:
        small = first_houses(root, args.houses_small, small_dir / "POVBench")
        for fmt in args.formats.split(","):
            rows = {args.houses_small: run(small, fmt), args.houses_large: run(root, fmt)}
            for r in rows.values():
                mb = r["bytes"] / 2**20
                shards = ", ".join(f"{s / 2**20:.0f}" for s in r["shards"])
                print(f"{fmt:8} {r['houses']:4} houses: {r['examples']:6} examples, {r['examples'] / r['wall']:7.1f} inst/s, "
                      f"{mb / r['wall']:6.1f} MB/s written ({mb:,.0f} MB in {r['wall']:.0f} s, {r['cpu']:.0f} s CPU), "
                      f"peak RSS {r['peak_rss_mb']:.0f} MB, {len(r['shards'])} shard(s) of MB: {shards}; load average {r['load']:.1f}")
            low, high = rows[args.houses_small], rows[args.houses_large]
            print(f"{fmt:8} peak memory {high['houses']} vs {low['houses']} houses: x{high['peak_rss_mb'] / low['peak_rss_mb']:.2f}")
    finally:
        shutil.rmtree(small_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
