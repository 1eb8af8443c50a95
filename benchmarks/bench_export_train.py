"""Export throughput and memory: instances/s, MB/s and peak memory at N and 10N houses.

Generates (or reuses) a dataset of --houses-large houses, exports its first --houses-small
houses and then all of them, each in a fresh process (so peak RSS is the export's own), in the
hf and messages formats. Memory should stay flat in the number of houses: an export streams
one shard at a time and a row group of at most 64 MB.

Usage: python benchmarks/bench_export_train.py [--houses-small 10] [--houses-large 100]
       [--dataset DIR]   (a generated set with at least --houses-large houses)
"""

from __future__ import annotations

import argparse
import json
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
root, out, fmt, houses = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3], int(sys.argv[4])
keep = sorted(p.name for p in (root / "artifacts").iterdir())[:houses]
split = "train=0:%d" % (max(int(h.rsplit("_", 1)[1]) for h in keep) + 1)
t0, c0 = time.perf_counter(), time.process_time()
r = export_training_set(root, out, ExportOptions(format=fmt, split=split), check_release=False)
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
shards = sorted(p.stat().st_size for p in (out / ("data" if fmt == "hf" else "messages")).glob("*") if p.is_file())
print(json.dumps({"examples": r.examples, "wall": wall, "cpu": cpu, "bytes": size, "shards": shards,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def run(root: Path, fmt: str, houses: int) -> dict:
    out = Path(tempfile.mkdtemp()) / "export"
    try:
        done = subprocess.run([sys.executable, "-c", CHILD, str(root), str(out), fmt, str(houses)], capture_output=True, text=True, check=True)
        return json.loads(done.stdout.strip().splitlines()[-1])
    finally:
        shutil.rmtree(out.parent, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--houses-small", type=int, default=10)
    ap.add_argument("--houses-large", type=int, default=100)
    ap.add_argument("--dataset", type=Path)
    args = ap.parse_args(argv)
    root = args.dataset
    if root is None:
        from povagent.generate import generate_dataset

        root = Path(tempfile.mkdtemp()) / "POVBench"
        t = time.perf_counter()
        generate_dataset(root, houses=args.houses_large, seed=0, jobs=2, progress=False)
        print(f"generated {args.houses_large} houses in {time.perf_counter() - t:.0f} s: {root}")
    for fmt in ("hf", "messages"):
        rows = {n: run(root, fmt, n) for n in (args.houses_small, args.houses_large)}
        for n, r in rows.items():
            mb = r["bytes"] / 2**20
            print(f"{fmt:8} {n:4} houses: {r['examples']:6} examples, {r['examples'] / r['wall']:7.1f} inst/s, "
                  f"{mb / r['wall']:6.1f} MB/s written ({mb:,.0f} MB, {r['cpu']:.1f} s CPU), peak RSS {r['peak_rss_mb']:.0f} MB, "
                  f"largest shard {max(r['shards']) / 2**20:.0f} MB of {len(r['shards'])}")
        small, large = rows[args.houses_small], rows[args.houses_large]
        print(f"{fmt:8} peak memory {args.houses_large} vs {args.houses_small} houses: x{large['peak_rss_mb'] / small['peak_rss_mb']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
