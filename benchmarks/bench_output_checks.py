"""What the output checks (``POVAGENT_CHECK_OUTPUTS=1``, on in the test suite) cost a run.

    python benchmarks/bench_output_checks.py [--rows 1000] [--rounds 3]

One synthetic release (:func:`povagent.testing.pytest_plugin.write_release`, 30 frames a house)
and the offline ``center`` backend with the ``basic`` strategy, ``json`` parser and ``official``
scorer; ``--rows`` keys are run into a fresh folder with the checks off and on, alternately, in
this one process (the variable is read at every write, so it can be turned on and off between
runs; one warm-up run of each first, so imports and the schema validators' construction are not
counted). The figure is the median over rounds of CPU(on) / CPU(off), with ``time.process_time``
(every thread of the process) and the load average. Writes ``benchmarks/results/bench_output_checks.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import tempfile
import time
from pathlib import Path

from results_file import figure, record

RUNS = 4


def run_once(data: Path, out: Path, rows: int, checked: bool) -> float:
    """CPU seconds of one run of ``rows`` keys with the checks on or off."""
    from povagent.config.models import PipelineConfig
    from povagent.config.plugin_checks import resolve_components
    from povagent.plugins import get_plugin_host
    from povagent.results.output_check import ENV
    from povagent.run.runner import PipelineRun

    host = get_plugin_host()
    config = resolve_components(
        PipelineConfig.model_validate({
            "dataset": {"path": str(data)}, "backend": "center", "strategy": "basic", "parser": "json",
            "scorers": ["official"], "concurrency": 16, "runs": RUNS, "cache": False,
            "instances": {"limit": rows // RUNS}, "output": str(out),
        }),
        host,
    )  # fmt: skip
    os.environ[ENV] = "1" if checked else "0"
    try:
        t = time.process_time()
        asyncio.run(PipelineRun(config, host=host).run())
        return time.process_time() - t
    finally:
        os.environ.pop(ENV, None)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=1000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    from povagent.testing.pytest_plugin import write_release

    with tempfile.TemporaryDirectory(prefix="bench_output_checks_") as tmp:
        work = Path(tmp)
        data = write_release(work / "data", houses=12, pairs=72, pair_directions=max(72, -(-args.rows // (3 * RUNS))), frames=30)
        for checked in (False, True):  # warm-up: imports, validators built
            run_once(data, work / f"warm_{checked}", RUNS * 3, checked)
        print(f"load before: {os.getloadavg()}")
        off, on, ratios = [], [], []
        for r in range(args.rounds):
            order = (False, True) if r % 2 == 0 else (True, False)
            got = {}
            for checked in order:
                got[checked] = run_once(data, work / f"run_{r}_{checked}", args.rows, checked)
            off.append(got[False])
            on.append(got[True])
            ratios.append(got[True] / got[False])
            print(f"round {r + 1}: checks off {got[False]:.2f} s CPU, on {got[True]:.2f} s CPU: {ratios[-1]:.2f}x", flush=True)
        ratio = statistics.median(ratios)
        load = os.getloadavg()
        print(f"output checks: {ratio:.2f}x the CPU of a run of {args.rows} rows; load after: {load}")
        record("bench_output_checks", [
            figure("run CPU with output checks over without", round(ratio, 2), "x",
                   comparison=f"{args.rows} rows, center backend, basic strategy, json parser, official scorer; median of {args.rounds} interleaved rounds"),
            figure(f"run CPU without checks, {args.rows} rows", round(statistics.median(off), 2), "s"),
            figure(f"run CPU with checks, {args.rows} rows", round(statistics.median(on), 2), "s"),
        ])


if __name__ == "__main__":
    main()
