"""Benchmark of scoring: CPU to score 100k official prediction rows, before and after.

Run: ``python benchmarks/bench_score.py [--dataset FOLDER] [--rows N] [--rounds R] [--baseline REF]``.

Generates a small dataset as ``povagent generate`` does (3 houses, unless ``--dataset`` names
one), synthesises ``--rows`` official prediction rows with a seeded generator (every pair and
direction of the release, the three conditions, a random frame of the house's exploration log,
random pixels in and around the image, some point lists, some unanswered rows and unknown
placements), writes them as one official predictions file, and scores it with official counting
(``score_predictions`` against ``read_release``, what ``povagent score`` does) with today's code
and with the ``povagent`` package of commit ``--baseline`` (the code before the ground truth was
computed once per instance), each in its own interpreter, alternating round by round. Prints the
CPU seconds (``time.process_time``: the machine is shared) of each round, the median ratio, and
checks that both summaries agree to 1e-12.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline_code import baseline_checkout, cpu_of
from results_file import figure, record

#: The last commit whose scorer recomputed each row's ground truth.
BEFORE = "43eae40"

SCORE = """
import json, time
from povagent.dataset.loader import load_dataset
from povagent.scoring.official_release import read_release
try:
    from povagent.results.prediction_files import score_predictions
except ImportError:  # a baseline from before the reader moved to results/
    from povagent.scoring.predictions import score_predictions
ds = load_dataset({dataset!r}, check_images=False)
release = read_release({dataset!r})
t = time.process_time()
summary, warnings = score_predictions({predictions!r}, ds, release)
print("cpu=", time.process_time() - t)
open({summary_out!r}, "w").write(json.dumps(summary, sort_keys=True))
"""


def synthesise_rows(dataset: Path, n: int, seed: int = 0) -> list[dict]:
    """``n`` official rows over the release's pairs, directions, conditions and frames."""
    from povagent.scoring.official_release import read_release

    release = read_release(dataset)
    rng = random.Random(seed)
    keys = sorted(release.pairs, key=str)
    logs = {h: sorted(release.log(h)) for h, _ in keys}
    rows = []
    for _ in range(n):
        house, pair = rng.choice(keys)
        placements = sorted(release.pairs[(house, pair)].get("placements", {}))
        direction = rng.choice(placements) if rng.random() > 0.02 else "front"
        cond = rng.choice("abc")
        row = {"house_id": house, "pair_id": pair, "direction": direction, "type": cond, "sentence": "",
               "predicted_x": rng.uniform(-50, 560), "predicted_y": rng.uniform(-50, 560), "parse_error": None}  # fmt: skip
        if cond != "c":
            row["predicted_image"] = rng.choice(logs[house])
        if rng.random() < 0.1:
            row["predicted_points"] = [[rng.uniform(0, 512), rng.uniform(0, 512)] for _ in range(rng.randint(1, 4))]
        if rng.random() < 0.03:
            row["predicted_x"] = row["predicted_y"] = None
        rows.append(row)
    return rows


def same(a, b, tol: float = 1e-12) -> bool:
    """Whether two JSON summaries agree, numbers to ``tol``."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k], tol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y, tol) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or abs(a - b) <= tol
    return a == b


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", type=Path, help="a generated dataset (default: generate 3 houses)")
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline", default=BEFORE, help=f"the commit timed as 'before' (default {BEFORE})")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        dataset = args.dataset
        if dataset is None:
            dataset = work / "dataset"
            from povagent.generate import generate_dataset

            generate_dataset(dataset, houses=3, seed=0, jobs=1, progress=False)  # what `povagent generate --houses 3` writes
        rows = synthesise_rows(dataset, args.rows)
        predictions = work / "predictions.json"
        predictions.write_text(json.dumps({"metadata": {"screen_width": 512, "screen_height": 512}, "predictions": rows}))
        old = baseline_checkout(args.baseline, work / "baseline")
        print(f"{len(rows)} rows over {len({(r['house_id'], r['pair_id'], r['direction']) for r in rows})} instances")
        cpu = {"before": [], "after": []}
        summaries = {}
        for k in range(args.rounds):
            for label, path in (("before", old), ("after", None)) if k % 2 == 0 else (("after", None), ("before", old)):
                out = work / f"{label}.json"
                code = SCORE.format(dataset=str(dataset), predictions=str(predictions), summary_out=str(out))
                cpu[label].append(cpu_of(code, path)["cpu"])
                summaries[label] = json.loads(out.read_text())
            print(f"round {k + 1}: before {cpu['before'][-1]:.2f} s CPU, after {cpu['after'][-1]:.2f} s CPU, "
                  f"ratio {cpu['after'][-1] / cpu['before'][-1]:.2f}")  # fmt: skip
        b, a = statistics.median(cpu["before"]), statistics.median(cpu["after"])
        print(f"median CPU to score {len(rows)} rows: before {b:.2f} s, after {a:.2f} s: {a / b:.2f}x (goal <= 0.4x)")
        print(f"summaries identical to 1e-12: {same(summaries['before'], summaries['after'])}")
        print(f"load average: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
        instances = len({(r["house_id"], r["pair_id"], r["direction"]) for r in rows})
        houses = len({r["house_id"] for r in rows})
        ratios = [x / y for x, y in zip(cpu["after"], cpu["before"])]
        beside = f"the scorer of commit {args.baseline}, same {len(rows)} rows, in-process CPU, rounds alternating"
        stem = "bench_score" if args.dataset is None else f"bench_score_{houses}_houses"
        print("wrote", record(stem, [
            figure(f"CPU to score {len(rows)} official rows, {houses} houses ({instances} instances), median of {args.rounds} rounds",
                   round(a / b, 2), "x", "<= 0.4x", beside),
            figure("smallest round ratio", round(min(ratios), 2), "x", "", beside),
            figure("largest round ratio", round(max(ratios), 2), "x", "", beside),
            figure("CPU before (median)", round(b, 2), "s", "", beside),
            figure("CPU after (median)", round(a, 2), "s", "", beside),
        ], note=f"summaries identical to 1e-12: {same(summaries['before'], summaries['after'])}"))  # fmt: skip


if __name__ == "__main__":
    main()
