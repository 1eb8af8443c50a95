"""What a multiple-choice run costs per item, beside lmms-eval's own scoring of the same items.

    python benchmarks/bench_choice_run.py --lmms-eval-utils FILE [--rounds 3] [--small 1000] [--large 10000]

A ViewSpatial-Bench file of ``--large`` records in the set's published format is written (each
record one of 40 distinct 512x512 PNG images, its questions, options and gold answers drawn from
the set's five question types), and its first ``--small`` records beside it. Then, each in a
fresh process of its own (so its peak RSS, ``VmHWM``, is its own):

* ``povagent``: a whole run of the set (the offline ``random`` backend answering a uniform label,
  the ``choice`` strategy, the set's official ``viewspatial`` parser and the ``choice`` scorer,
  concurrency 16), from opening the set to ``summary.json`` written: CPU time (user + system);
* ``lmms-eval``: lmms-eval's own scoring of the same records and the same replies (the answers
  the run's rows hold): its ``viewspatial_process_results`` for each record, then its six
  aggregations, from ``--lmms-eval-utils``: the file ``lmms_eval/tasks/viewspatial/utils.py``
  of EvolvingLMMs-Lab/lmms-eval at commit 75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3 (fetch the
  repository and ``git show 75571cfe...:lmms_eval/tasks/viewspatial/utils.py > FILE``, outside
  this repository; it is run, never copied here). CPU time of the scoring alone.

The figure is each side's CPU per added item, ``(cpu(large) - cpu(small)) / (large - small)``,
and their ratio (goal: povagent at most 20x lmms-eval's; issue 55), the median over
``--rounds`` rounds, beside the run's peak RSS at ``--large`` over ``--small`` items (goal:
<= 1.1). Prints each round with the load average; writes ``benchmarks/results/bench_choice_run.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import importlib.util
import json
import os
import random
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from baseline_code import child_json, cpu_seconds, peak_rss_mib
from results_file import figure, record

#: ViewSpatial-Bench's question types (its ``question_type`` values), one drawn per record.
QUESTION_TYPES = (
    "Camera perspective - Relative Direction",
    "Camera perspective - Object View Orientation",
    "Person perspective - Relative Direction",
    "Person perspective - Object View Orientation",
    "Person perspective - Scene Simulation Relative Direction",
)
OPTIONS = ("right", "left", "front", "back")
IMAGES = 40


def write_set(folder: Path, large: int, small: int) -> dict[str, Path]:
    """``{size: file}``: a ViewSpatial-Bench file of ``large`` records and one of its first
    ``small``, over :data:`IMAGES` distinct PNG images in ``folder/images``."""
    import numpy as np
    from PIL import Image

    (folder / "images").mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    for i in range(IMAGES):
        Image.fromarray(rng.integers(0, 255, size=(512, 512, 3), dtype=np.uint8)).save(folder / "images" / f"scene_{i:02d}.png", compress_level=1)
    pick = random.Random(0)
    records = []
    for i in range(large):
        options = pick.sample(OPTIONS, len(OPTIONS))
        gold = pick.randrange(len(options))
        choices = "\n".join(f"{'ABCD'[k]}. {o}" for k, o in enumerate(options))
        records.append({
            "question_type": pick.choice(QUESTION_TYPES),
            "image_path": [f"images/scene_{pick.randrange(IMAGES):02d}.png"],
            "question": f"From the camera's view, where is object {i} relative to object {i + 1}?",
            "answer": f"{'ABCD'[gold]}. {options[gold]}",
            "choices": choices,
        })  # fmt: skip
    files = {"large": folder / f"viewspatial_{large}.json", "small": folder / f"viewspatial_{small}.json"}
    files["large"].write_text(json.dumps(records))
    files["small"].write_text(json.dumps(records[:small]))
    return files


def one_run(set_file: Path, out: Path) -> dict[str, Any]:
    """A choice run of ``set_file`` in this process: CPU seconds and peak RSS; the replies."""
    from povagent.config.models import PipelineConfig
    from povagent.config.plugin_checks import resolve_components
    from povagent.plugins import get_plugin_host
    from povagent.results.rows import iter_rows
    from povagent.run.runner import PipelineRun

    host = get_plugin_host()
    config = resolve_components(
        PipelineConfig.model_validate({
            "dataset": {"path": str(set_file), "format": "viewspatial"},
            "backend": "random",
            "strategy": "choice",
            "scorers": ["choice"],
            "concurrency": 16,
            "runs": 1,
            "cache": False,
            "output": str(out),
        }),
        host,
    )  # fmt: skip
    cpu0 = cpu_seconds()
    result = asyncio.run(PipelineRun(config, host=host).run())
    cpu = cpu_seconds() - cpu0
    peak = peak_rss_mib()
    replies = {int(row.pair_id): row.exchanges[-1].raw for row in iter_rows(out / "results.jsonl")}
    (out / "replies.json").write_text(json.dumps([replies[i] for i in range(len(replies))]))
    return {"items": result.summary.rows.done, "peak_mib": peak, "cpu_s": cpu,
            "accuracy": result.summary.metrics["choice"].overall["accuracy"].value}  # fmt: skip


def lmms_eval_scoring(utils: Path, set_file: Path, replies_file: Path) -> dict[str, Any]:
    """lmms-eval's scoring of the records of ``set_file`` with ``replies_file``'s answers, in
    this process: its process_results for each record, then its aggregations; CPU seconds."""
    spec = importlib.util.spec_from_file_location("lmms_eval_viewspatial_utils", utils)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    docs = json.loads(set_file.read_text())
    replies = json.loads(replies_file.read_text())
    t = time.process_time()
    per_doc = [module.viewspatial_process_results(doc, [reply]) for doc, reply in zip(docs, replies, strict=True)]
    by_metric: dict[str, list[dict]] = {}
    for result in per_doc:
        for metric, value in result.items():
            by_metric.setdefault(metric, []).append(value)
    scores = {"overall_accuracy": module.viewspatial_aggregate_results(by_metric["overall_accuracy"])}
    for key in module.VIEWSPATIAL_QUESTION_TYPES.values():
        scores[f"{key}_accuracy"] = getattr(module, f"viewspatial_aggregate_{key}")(by_metric[f"{key}_accuracy"])
    cpu = time.process_time() - t
    return {"items": len(per_doc), "cpu_s": cpu, "accuracy": scores["overall_accuracy"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lmms-eval-utils", type=Path, required=False, help="lmms_eval/tasks/viewspatial/utils.py at 75571cfe")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--small", type=int, default=1000)
    parser.add_argument("--large", type=int, default=10000)
    parser.add_argument("--child", choices=("run", "lmms"), help=argparse.SUPPRESS)
    parser.add_argument("--set", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child == "run":
        print(json.dumps(one_run(args.set, args.out)))
        return
    if args.child == "lmms":
        print(json.dumps(lmms_eval_scoring(args.lmms_eval_utils, args.set, args.out / "replies.json")))
        return
    if args.lmms_eval_utils is None or not args.lmms_eval_utils.is_file():
        sys.exit("--lmms-eval-utils: give lmms-eval's lmms_eval/tasks/viewspatial/utils.py at commit 75571cfe (see the docstring)")
    with tempfile.TemporaryDirectory(prefix="bench_choice_run_") as tmp:
        work = Path(tmp)
        files = write_set(work / "set", args.large, args.small)
        print(f"load before: {os.getloadavg()}")
        got: dict[str, dict[str, list[dict[str, Any]]]] = {k: {"small": [], "large": []} for k in ("povagent", "lmms-eval")}
        for r in range(args.rounds):
            for size in ("small", "large") if r % 2 == 0 else ("large", "small"):
                out = work / f"run_{size}"
                shutil.rmtree(out, ignore_errors=True)
                got["povagent"][size].append(child_json(__file__, ["--child", "run", "--set", str(files[size]), "--out", str(out)], None))
                got["lmms-eval"][size].append(child_json(__file__, ["--child", "lmms", "--lmms-eval-utils", str(args.lmms_eval_utils),
                                                                    "--set", str(files[size]), "--out", str(out)], None))  # fmt: skip
                ours, theirs = got["povagent"][size][-1], got["lmms-eval"][size][-1]
                assert abs(ours["accuracy"] - theirs["accuracy"]) < 1e-12, (ours, theirs)  # the same items and replies, scored alike
            print(
                f"round {r + 1}: "
                + "; ".join(f"{who} {got[who]['small'][-1]['cpu_s']:.3f} -> {got[who]['large'][-1]['cpu_s']:.3f} s CPU" for who in got)
                + f"; povagent peak {got['povagent']['small'][-1]['peak_mib']:.1f} -> {got['povagent']['large'][-1]['peak_mib']:.1f} MiB",
                flush=True,
            )
        load = os.getloadavg()
        added = args.large - args.small
        per_item = {who: [(b["cpu_s"] - s["cpu_s"]) / added for s, b in zip(by["small"], by["large"], strict=True)] for who, by in got.items()}
        ratio = statistics.median(o / t for o, t in zip(per_item["povagent"], per_item["lmms-eval"], strict=True))
        peak = statistics.median(b["peak_mib"] / s["peak_mib"] for s, b in zip(got["povagent"]["small"], got["povagent"]["large"], strict=True))
        ours_ms, theirs_ms = 1000 * statistics.median(per_item["povagent"]), 1000 * statistics.median(per_item["lmms-eval"])
        whole = statistics.median(b["cpu_s"] for b in got["povagent"]["large"]) / statistics.median(b["cpu_s"] for b in got["lmms-eval"]["large"])
        print(f"CPU per added item: povagent {ours_ms:.4f} ms, lmms-eval {theirs_ms:.4f} ms: {ratio:.1f}x (goal <= 20); "
              f"peak RSS {args.large} / {args.small} items: {peak:.3f}x (goal <= 1.1); load after: {load}")  # fmt: skip
        setting = (f"a ViewSpatial-Bench file of {args.large:,} records over {IMAGES} images; random backend, choice strategy, "
                   f"viewspatial parser, choice scorer; median of {args.rounds} rounds, each side in its own process")  # fmt: skip
        record("bench_choice_run", [
            figure("choice run CPU per added item / lmms-eval's scoring per added item", round(ratio, 1), "x", target="<= 20",
                   comparison=f"lmms-eval 75571cfe viewspatial_process_results + aggregations, same records and replies; {setting}"),
            figure("choice run CPU per added item", round(ours_ms, 4), "ms", comparison=f"items {args.small:,} -> {args.large:,}"),
            figure("lmms-eval scoring CPU per added item", round(theirs_ms, 4), "ms", comparison=f"items {args.small:,} -> {args.large:,}"),
            figure(f"choice run CPU at {args.large:,} items / lmms-eval's scoring", round(whole, 1), "x",
                   comparison="whole run (set opened, answered, parsed, scored, written, summarized) vs scoring alone"),
            figure(f"choice run peak RSS, {args.large:,} items over {args.small:,}", round(peak, 3), "x", target="<= 1.1"),
        ])  # fmt: skip


if __name__ == "__main__":
    main()
