"""Does ``povagent report``'s memory stay flat as a run's rows grow? Peak RSS at 1,000 rows and at 10,000.

    python benchmarks/bench_report_memory.py [--rounds 3] [--small 1000] [--large 10000] [--baseline 5f3474e]

The runs are made as :mod:`bench_run_memory` makes them (one synthetic release of the paper's
full shape, the offline ``center`` backend with the real ``basic`` strategy, ``json`` parser and
``official`` scorer, ``runs: 4``), once each, with today's code. Then the report of each run
folder is written without the gallery (its pages are bounded by ``--gallery-limit``; the tables,
plots and bootstrap CIs are what must not grow with the rows), each report in a fresh process of
its own so that its peak RSS (``VmHWM``) is its own, with today's code and with the ``povagent``
package of commit ``--baseline`` (:mod:`baseline_code`). Rounds alternate the order (the machine
is shared); the figure is the median over rounds of peak(large) / peak(small), printed with the
CPU time (user + system) of each report and the load average.
Writes ``benchmarks/results/bench_report_memory.json``.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import tempfile
from pathlib import Path
from typing import Any

from baseline_code import baseline_checkout, before_after_rounds, child_json, cpu_seconds, peak_medians, peak_rss_mib
from bench_run_memory import RUNS, measure, memory_arguments
from results_file import figure, record


def one_report(run: Path, data: Path, out: Path) -> dict[str, Any]:
    """The report of ``run`` (no gallery) in this process; its peak RSS and CPU seconds."""
    from povagent.report.build import write_report

    cpu0 = cpu_seconds()
    write_report(run, out, dataset_path=data, gallery=False)
    cpu = cpu_seconds() - cpu0
    return {"peak_mib": peak_rss_mib(), "cpu_s": cpu}


def report_in_process(run: Path, data: Path, out: Path, pythonpath: Path | None) -> dict[str, Any]:
    """One report in a fresh process (``pythonpath``: the baseline's code first on the path)."""
    shutil.rmtree(out, ignore_errors=True)
    return child_json(__file__, ["--child", str(run), "--data", str(data), "--out", str(out)], pythonpath)


def main() -> None:
    args = memory_arguments(__doc__, "5f3474e", Path)
    if args.child:
        print(json.dumps(one_report(args.child, args.data, args.out)))
        return
    from povagent.testing.pytest_plugin import write_release

    with tempfile.TemporaryDirectory(prefix="bench_report_memory_") as tmp:
        work = Path(tmp)
        data = write_release(work / "data", houses=47, pairs=288, pair_directions=max(813, -(-args.large // (3 * RUNS))), frames=30)
        rows = {size: measure(data, work, n, "run", None)["rows"] for size, n in (("small", args.small), ("large", args.large))}
        runs = {size: work / f"run_run_{n}" for size, n in (("small", args.small), ("large", args.large))}
        old = baseline_checkout(args.baseline, work / "baseline")
        print(f"load before: {os.getloadavg()}")

        def round_done(r: int, got: dict) -> None:
            print(f"round {r + 1}: " + "; ".join(
                f"{label} {got[label]['small'][-1]['peak_mib']:.1f} -> {got[label]['large'][-1]['peak_mib']:.1f} MiB "
                f"({got[label]['small'][-1]['cpu_s']:.1f} -> {got[label]['large'][-1]['cpu_s']:.1f} s CPU)" for label in ("before", "after")), flush=True)

        got = before_after_rounds(
            args.rounds, old, lambda label, path, size: report_in_process(runs[size], data, work / f"report_{label}_{size}", path), round_done
        )
        load = os.getloadavg()
        med = {label: peak_medians(by) for label, by in got.items()}
        for label in got:
            print(f"{label}: report peak {med[label]['small']:.1f} MiB at {rows['small']} rows, {med[label]['large']:.1f} MiB at "
                  f"{rows['large']} rows: {med[label]['ratio']:.3f}x")
        a, b = med["after"], med["before"]
        cpu_ratio = statistics.median(x["cpu_s"] / y["cpu_s"] for x, y in zip(got["after"]["large"], got["before"]["large"], strict=True))
        print(f"after: {a['ratio']:.3f}x (target <= 1.1); report CPU at {rows['large']} rows after / before: {cpu_ratio:.3f}x; load after: {load}")
        before = f"before (commit {args.baseline})"
        record("bench_report_memory", [
            figure(f"report peak RSS, {rows['large']:,} rows over {rows['small']:,}", round(a["ratio"], 3), "x", target="<= 1.1",
                   comparison=f"{before}: {b['ratio']:.3f}x; no gallery; center backend, basic strategy, json parser, official "
                   f"scorer, {RUNS} runs; median of {args.rounds} rounds, each report in its own process"),
            figure(f"report peak RSS at {rows['large']:,} rows", round(a["large"], 1), "MiB", comparison=f"{before}: {b['large']:.1f} MiB"),
            figure(f"report peak RSS at {rows['small']:,} rows", round(a["small"], 1), "MiB", comparison=f"{before}: {b['small']:.1f} MiB"),
            figure(f"report CPU at {rows['large']:,} rows", round(a["cpu_large"], 1), "s", comparison=f"{before}: {b['cpu_large']:.1f} s"),
            figure(f"report CPU at {rows['large']:,} rows / before's", round(cpu_ratio, 3), "x", target="<= 1.05",
                   comparison=f"{before}, the same run folder; median of the {args.rounds} rounds' ratios (user + system CPU)"),
        ])


if __name__ == "__main__":
    main()
