"""Does a run's memory stay flat as its rows grow? Peak RSS at 1,000 rows and at 10,000.

    python benchmarks/bench_run_memory.py [--rounds 3] [--small 1000] [--large 10000] [--baseline f33d9c8]

One synthetic release of the paper's full shape (:func:`povagent.testing.pytest_plugin.write_release`:
47 houses, 813 pair-directions, 30 frames of 512x512 each: 2,439 instances) is written once;
then the offline ``center`` backend with the real ``basic`` strategy, ``json`` parser and
``official`` scorer runs ``--small`` rows and ``--large`` rows (``runs: 4``, the instances
limited to a quarter of the rows), each run in a fresh process of its own so that its peak RSS
(``VmHWM``) is its own, with today's code and with the ``povagent`` package of commit
``--baseline`` (:mod:`baseline_code`). Rounds alternate the order (the machine is shared); the
figure is the median over rounds of peak(large) / peak(small), held to <= 1.1 (a run keeps no
state per key while it runs: its summary reads the rows back from results.jsonl at the end). CPU
time (user + system) per run is printed beside it, with the load average.
Writes ``benchmarks/results/bench_run_memory.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import statistics
import tempfile
from pathlib import Path
from typing import Any

from baseline_code import baseline_checkout, before_after_rounds, child_json, cpu_seconds, peak_medians, peak_rss_mib
from results_file import figure, record

RUNS = 4  # each instance 4 times: 2,500 instances x 4 = 10,000 rows


def one_run(data: Path, out: Path, rows: int) -> dict[str, Any]:
    """Run ``rows`` keys in this process; its peak RSS and CPU seconds."""
    from povagent.config.models import PipelineConfig
    from povagent.config.plugin_checks import resolve_components
    from povagent.plugins import get_plugin_host
    from povagent.run.runner import PipelineRun

    host = get_plugin_host()
    config = resolve_components(
        PipelineConfig.model_validate({
            "dataset": {"path": str(data)},
            "backend": "center",
            "strategy": "basic",
            "parser": "json",
            "scorers": ["official"],
            "concurrency": 16,
            "runs": RUNS,
            "cache": False,
            "instances": {"limit": rows // RUNS},
            "output": str(out),
        }),
        host,
    )
    cpu0 = cpu_seconds()
    result = asyncio.run(PipelineRun(config, host=host).run())
    cpu = cpu_seconds() - cpu0
    return {"rows": result.summary.rows.done, "peak_mib": peak_rss_mib(), "cpu_s": cpu}


def measure(data: Path, workdir: Path, rows: int, label: str, pythonpath: Path | None) -> dict[str, Any]:
    """One run in a fresh process (``pythonpath``: the baseline's code first on the path)."""
    out = workdir / f"run_{label}_{rows}"
    shutil.rmtree(out, ignore_errors=True)
    return child_json(__file__, ["--child", str(rows), "--data", str(data), "--out", str(out)], pythonpath)


def memory_arguments(doc: str | None, baseline: str, child: type) -> argparse.Namespace:
    """The command line of a benchmark of memory at two sizes (this one and :mod:`bench_report_memory`):
    rounds, the two sizes, the commit measured as "before", and what its child process is told."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--small", type=int, default=1000)
    parser.add_argument("--large", type=int, default=10000)
    parser.add_argument("--baseline", default=baseline, help="the commit measured as 'before'")
    parser.add_argument("--child", type=child, help=argparse.SUPPRESS)
    parser.add_argument("--data", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    return parser.parse_args()


def main() -> None:
    args = memory_arguments(__doc__, "f33d9c8", int)
    if args.child:
        print(json.dumps(one_run(args.data, args.out, args.child)))
        return
    from povagent.testing.pytest_plugin import write_release

    with tempfile.TemporaryDirectory(prefix="bench_run_memory_") as tmp:
        work = Path(tmp)
        # enough pair-directions for --large rows: 3 conditions each, RUNS runs each
        data = write_release(work / "data", houses=47, pairs=288, pair_directions=max(813, -(-args.large // (3 * RUNS))), frames=30)
        old = baseline_checkout(args.baseline, work / "baseline")
        print(f"load before: {os.getloadavg()}")
        sizes = {"small": args.small, "large": args.large}

        def round_done(r: int, got: dict) -> None:
            print(f"round {r + 1}: " + "; ".join(
                f"{label} {got[label]['small'][-1]['peak_mib']:.1f} -> {got[label]['large'][-1]['peak_mib']:.1f} MiB "
                f"({got[label]['large'][-1]['cpu_s']:.1f} s CPU at {got[label]['large'][-1]['rows']} rows)" for label in ("before", "after")), flush=True)

        got = before_after_rounds(args.rounds, old, lambda label, path, size: measure(data, work, sizes[size], label, path), round_done)
        load = os.getloadavg()
        med: dict[str, dict[str, float]] = {}
        for label, by in got.items():
            small, large = by["small"], by["large"]
            med[label] = {
                **peak_medians(by),
                "per_row_kib": 1024 * statistics.median(b["peak_mib"] - s["peak_mib"] for s, b in zip(small, large))
                / (large[0]["rows"] - small[0]["rows"]),
            }
            print(f"{label}: peak {med[label]['small']:.1f} MiB at {small[0]['rows']} rows, {med[label]['large']:.1f} MiB at "
                  f"{large[0]['rows']} rows: {med[label]['ratio']:.3f}x, {med[label]['per_row_kib']:.2f} KiB per extra row")
        a, b = med["after"], med["before"]
        n_small, n_large = got["after"]["small"][0]["rows"], got["after"]["large"][0]["rows"]
        cpu_ratio = statistics.median(x["cpu_s"] / y["cpu_s"] for x, y in zip(got["after"]["large"], got["before"]["large"], strict=True))
        print(f"after: {a['ratio']:.3f}x (target <= 1.1); run CPU at {n_large} rows after / before: {cpu_ratio:.3f}x; load after: {load}")
        before = f"before (commit {args.baseline})"
        record("bench_run_memory", [
            figure(f"peak RSS, {n_large:,} rows over {n_small:,}", round(a["ratio"], 3), "x", target="<= 1.1",
                   comparison=f"{before}: {b['ratio']:.3f}x; center backend, basic strategy, json parser, official scorer, "
                   f"concurrency 16; median of {args.rounds} rounds, each run in its own process"),
            figure(f"peak RSS at {n_large:,} rows", round(a["large"], 1), "MiB", comparison=f"{before}: {b['large']:.1f} MiB"),
            figure(f"peak RSS at {n_small:,} rows", round(a["small"], 1), "MiB", comparison=f"{before}: {b['small']:.1f} MiB"),
            figure("peak RSS per extra row", round(a["per_row_kib"], 2), "KiB", comparison=f"{before}: {b['per_row_kib']:.2f} KiB"),
            figure(f"run CPU at {n_large:,} rows", round(a["cpu_large"], 1), "s", comparison=f"{before}: {b['cpu_large']:.1f} s"),
            figure(f"run CPU at {n_large:,} rows / before's", round(cpu_ratio, 3), "x", target="<= 1.05",
                   comparison=f"{before}, the same rows; median of the {args.rounds} rounds' ratios (user + system CPU)"),
        ])


if __name__ == "__main__":
    main()
