"""How fast ``povagent report`` is at the release's scale (2,439 instances), and how big.

Three measurements in one run:

1. Gallery + page: a sweep of simulated cells on a (generated) dataset with real rendered
   frames, enough cells that the gallery holds about 2,439 drawings; every answer carries a
   chain-of-thought-length text (~2,500 characters, like the paper's CoT answers). The report
   is written twice: cold (every image drawn) and warm (every image found by hash and
   skipped). Prints times, the cold/warm ratio, per-image cost, and the sizes of the page, the
   answers files, the images and the cards' frame strips (one image per house).
2. Opening the page: headless Chromium loads ``report.html`` from disk; prints the page's own
   time from script start to the first gallery page drawn (``data-render-ms``) and the
   browser's wall time including start-up.
3. Statistics: one system with 2,439 instances x 3 runs (synthetic observations), all tables'
   bootstrap CIs (2,000 resamples each).

Usage: ``python benchmarks/report_speed.py [--dataset PATH] [--target 2439] [--workers N]``.
Without ``--dataset`` a 6-house dataset is generated first (about a minute).
"""

from __future__ import annotations

import argparse
import json
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.instances import row_key
from povagent.dataset.loader import load_dataset
from povagent.report.analysis import analyze
from povagent.report.build import write_report
from povagent.report.collect import Collection, Observation
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, ResultsWriter, RowStatus
from povagent.scoring.normalized_l2 import score_point

#: A chain-of-thought-length preamble (~2,500 characters) before each simulated answer's JSON.
REASONING = (
    "Step 1 - Observer: the sentence says where the speaker was and what they were doing. "
    "Step 2 - Frames: I look for the frame that shows the anchor seen from that side. "
    "Step 3 - Direction: left and right are taken from the observer facing the anchor. "
) * 10


def simulated_cell(folder: Path, dataset, instances, seed: int) -> None:
    """One run folder: a noisy simulated model answering every instance."""
    folder.mkdir(parents=True)
    cfg = {"dataset": {"path": str(dataset.root.resolve())}, "backend": {"name": "sim", "options": {"model": f"sim-{seed}"}}, "strategy": {"name": "basic"}}
    (folder / "config.yaml").write_text(yaml.safe_dump(cfg))
    rng = random.Random(seed)
    with ResultsWriter(folder / "results.jsonl") as w:
        for inst in instances:
            k = rng.randrange(len(inst.frames)) if inst.condition.uses_exploration_frames else None
            frame = inst.frames[k or 0]
            x, y = rng.uniform(0, 511), rng.uniform(0, 511)
            answered = rng.random() < 0.9
            parsed = ParsedAnswer(status=ParseStatus.OK, selected_image=k, x=x, y=y) if answered else ParsedAnswer(status=ParseStatus.UNPARSEABLE)
            score = score_point(inst, frame, x, y).as_dict() if answered else {"answered": False, "l2": None}
            w.write(
                ResultRow(
                    key=row_key(inst.id, 0), instance_id=inst.id, house_id=inst.house_id, pair_id=inst.pair_id,
                    direction=str(inst.direction), condition=str(inst.condition), sentence=inst.sentence,
                    status=RowStatus.ANSWERED if answered else RowStatus.PARSE_ERROR,
                    exchanges=[ExchangeRecord(request_hash="sim", raw=REASONING + json.dumps({"selected_image": k, "x": x, "y": y}))],
                    parse=parsed,
                    prediction=Prediction(selected_image=k, image_path=frame.image_path if k is not None else None, x=x, y=y) if answered else Prediction(),
                    scores={"official": score},
                )
            )


def synthetic_collection(n_instances: int = 2439, runs: int = 3) -> Collection:
    """One system's observations at full scale, without a dataset."""
    rng = random.Random(0)
    obs = []
    for i in range(n_instances):
        cond, direction = "abc"[i % 3], ("right", "left", "front", "up")[i % 4]
        for r in range(runs):
            answered = rng.random() < 0.85
            l2 = rng.random() * 0.8 if answered else None
            obs.append(Observation("sim", "run", r, f"h/{i}/{direction}/{cond}", "h", str(i), direction, cond, "answered" if answered else "parse_error",
                                   "ok" if answered else "unparseable", answered, l2, l2, answered or None, False if answered else None,
                                   0.5, 0.5, 0, None, 10.0, 10.0, "", None))
    return Collection(Path("synthetic"), [], obs)


def open_in_chromium(page: Path, profile: Path) -> tuple[int, float] | None:
    """(the page's own ms to its first gallery page, browser wall seconds), or None without Chromium."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        return None
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
           f"--user-data-dir={profile}", "--virtual-time-budget=10000", "--dump-dom", page.as_uri()]
    t = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    wall = time.perf_counter() - t
    m = re.search(r'<body[^>]*data-render-ms="(\d+)"', done.stdout)
    return (int(m.group(1)) if m else -1), wall


def main(argv: list[str] | None = None) -> int:
    """Run both measurements and print the figures."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset")
    ap.add_argument("--target", type=int, default=2439, help="gallery drawings to make")
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="report_speed_"))
    try:
        if args.dataset:
            root = Path(args.dataset)
        else:
            from povagent.generate.dataset import generate_dataset

            root = tmp / "POVBench"
            generate_dataset(root, houses=6, seed=0, progress=False)
        ds = load_dataset(root)
        instances = ds.instances()
        cells = max(1, -(-args.target // len(instances)))
        sweep = tmp / "sweep"
        for c in range(cells):
            simulated_cell(sweep / f"cell_{c:02d}", ds, instances, seed=c)
        n = cells * len(instances)
        t = time.perf_counter()
        cold = write_report(sweep, tmp / "report", workers=args.workers)
        t_cold = time.perf_counter() - t
        t = time.perf_counter()
        warm = write_report(sweep, tmp / "report", workers=args.workers)
        t_warm = time.perf_counter() - t
        images = list((tmp / "report" / "images").iterdir())
        size_img = sum(p.stat().st_size for p in images)
        page = (tmp / "report" / "report.html").stat().st_size
        print(f"gallery: {n} predictions ({cells} cells x {len(instances)} instances), {cold.gallery.drawn} drawings")
        print(
            f"cold report: {t_cold:.1f} s (gallery {cold.timings['gallery']:.1f} s = {1000 * cold.timings['gallery'] / max(1, cold.gallery.drawn):.1f} "
            f"ms/drawing; statistics {cold.timings['statistics']:.1f} s)"
        )
        print(
            f"warm report: {t_warm:.1f} s (gallery {warm.timings['gallery']:.2f} s, {warm.gallery.cached} reused); cold/warm gallery = "
            f"{cold.timings['gallery'] / max(1e-9, warm.timings['gallery']):.0f}x"
        )
        answers = list((tmp / "report" / "answers").iterdir())
        size_ans = sum(p.stat().st_size for p in answers)
        print(f"sizes: report.html {page / 1e6:.2f} MB; answers {len(answers)} files, {size_ans / 1e6:.1f} MB "
              f"(loaded one at a time when a card is opened); images {len(images)} files, {size_img / 1e6:.1f} MB "
              f"({size_img / max(1, len(images)) / 1e3:.1f} kB/file)")
        strips = [p for p in images if p.name.endswith(".s.jpg")]
        size_strips = sum(p.stat().st_size for p in strips)
        frames = sum(s["n"] for s in cold.gallery.strips)
        print(f"frame strips: {len(strips)} houses, {frames} frames, {size_strips / 1e3:.0f} kB "
              f"({size_strips / max(1, frames):.0f} B/frame, {100 * size_strips / max(1, size_img):.1f}% of the images); "
              f"{len(cold.gallery.views)} distinct GT-view lists for {n} cards")
        opened = open_in_chromium(tmp / "report" / "report.html", tmp / "chromium-profile")
        if opened is None:
            print("opening: chromium not found, not measured")
        else:
            print(f"opening in headless Chromium: {opened[0]} ms from script start to the first gallery page; "
                  f"{opened[1]:.1f} s wall including browser start-up")
        t = time.perf_counter()
        a = analyze(synthetic_collection(), None)
        print(
            f"statistics at 2,439 instances x 3 runs, one system: {time.perf_counter() - t:.2f} s ({len(a.systems[0].by_condition_direction)} cells + "
            "conditions + directions, 2,000 resamples per CI)"
        )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
