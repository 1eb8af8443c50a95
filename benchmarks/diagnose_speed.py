"""The whole ``rescore`` with ``diagnose`` + ``relation``, at the paper's size, before and after.

The goal (issue 26): the paper-size set, 2,439 instances x 10 systems, rescored with
``--scorer diagnose --scorer relation`` in under 60 s of CPU. Measured directly, not scaled:

1. on a generated set (``--dataset``; ``povagent generate --houses 47`` makes about 2,600
   instances, the paper has 2,439), makes one finished run per system of :data:`SYSTEMS`: ten
   offline systems (planted behaviour simulations over the basic, CoT, S-CoT and O-Plot
   prompts, and the center, random and oracle baselines), each answering every instance of
   the three conditions once (``--runs-dir`` keeps them for another time);
2. rescores all ten runs whole, as a user does: ``povagent rescore RUN --scorer diagnose
   --scorer relation``, one process per run (interpreter start and imports, loading the set,
   re-parsing, the run's official scorer and the two scorers, writing the rows, the summary
   with its bootstrap, the console tables), with today's code and with the ``povagent`` and
   ``povagent_plugins`` packages of commit ``--baseline``, alternating round by round so both
   see the same machine load. What is timed is the CPU time (user + system) of those processes
   (``getrusage``: the machine is shared, wall time would measure the other jobs). Official-only
   rescoring (``povagent rescore RUN``) is timed the same way;
3. prints each round, the median CPU seconds and the after/before ratio, whether the ten
   summaries of both codes agree to 1e-12, and the load average.

Usage::

    python benchmarks/diagnose_speed.py --dataset D [--runs-dir R] [--rounds 3] [--baseline REF]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from baseline_code import baseline_checkout
from bench_score import same

#: The code before this benchmark's speed-ups (the per-row fsync, the parse of every row's
#: request, the per-answer projections).
BEFORE = "a516910"
PAPER_INSTANCES = 2439
GOAL_S = 60.0

#: Ten offline systems: (backend, strategy). Planted simulations answer in every prompt's JSON
#: format; the baselines answer every instance too.
SYSTEMS: dict[str, tuple[dict[str, Any], str]] = {
    "planted-truth-basic": ({"name": "planted", "options": {"pixel_sigma": 5, "seed": 0}}, "basic"),
    "planted-ego40-basic": ({"name": "planted", "options": {"egocentric": 0.4, "pixel_sigma": 5, "seed": 0}}, "basic"),
    "planted-mirror30-basic": ({"name": "planted", "options": {"mirror": 0.3, "pixel_sigma": 5, "seed": 0}}, "basic"),
    "planted-rf30-basic": ({"name": "planted", "options": {"random_frame": 0.3, "pixel_sigma": 5, "seed": 0}}, "basic"),
    "planted-mix-cot": ({"name": "planted", "options": {"egocentric": 0.2, "mirror": 0.1, "random_frame": 0.1, "seed": 1}}, "cot"),
    "planted-ego40-scot": ({"name": "planted", "options": {"egocentric": 0.4, "seed": 2}}, "spatial-cot"),
    "planted-ego20-oplot": ({"name": "planted", "options": {"egocentric": 0.2, "seed": 3}}, "o-plot"),
    "center": ({"name": "center", "options": {"frame_policy": "random", "seed": 0}}, "basic"),
    "random": ({"name": "random", "options": {"seed": 0}}, "basic"),
    "oracle": ({"name": "oracle", "options": {}}, "basic"),
}

def rescore_cpu(runs: list[Path], extra: tuple[str, ...], pythonpath: Path | None) -> tuple[float, list[dict[str, Any]]]:
    """CPU seconds of ``povagent rescore RUN [--scorer ...]`` run as a user runs it, one process
    per run (interpreter start, imports, the rescore, the console tables), with ``pythonpath``
    first on the import path (``None``: today's code); and the summaries the runs wrote."""
    env = dict(os.environ)
    if pythonpath is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(pythonpath), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    summaries = []
    for run in runs:
        command = [sys.executable, "-m", "povagent.cli", "rescore", str(run), *(a for name in extra for a in ("--scorer", name))]
        # outside the repository: ``-m`` puts the working folder first on the path
        subprocess.run(command, env=env, cwd=tempfile.gettempdir(), check=True, capture_output=True, timeout=3600)
        summary = json.loads((run / "rescored-official" / "summary.json").read_text())
        summaries.append({k: v for k, v in summary.items() if k != "source_run"})
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), summaries


def make_runs(dataset: Path, folder: Path) -> list[Path]:
    """One finished run per system (kept when already complete in ``folder``)."""
    from povagent.config.pipeline import pipeline_from_source
    from povagent.config.yaml_reader import ConfigSource
    from povagent.run.runner import PipelineRun

    out = []
    for name, (backend, strategy) in SYSTEMS.items():
        run = folder / name
        if not (run / "summary.json").exists():
            config = pipeline_from_source(ConfigSource("<speed>", {
                "dataset": {"path": str(dataset)}, "backend": backend, "strategy": strategy, "parser": "official",
                "scorers": ["official"], "cache": False, "output": str(run),
            }, {}))  # fmt: skip
            asyncio.run(PipelineRun(config).run())
        out.append(run)
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset", type=Path, required=True, help="a generated set (povagent generate --houses 47 for the paper's size)")
    parser.add_argument("--runs-dir", type=Path, help="where the ten runs are made (kept; default: a temporary folder)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline", default=BEFORE, help=f"the commit timed as 'before' (default {BEFORE})")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="diagnose_speed_"))
    runs = make_runs(args.dataset, args.runs_dir or work / "runs")
    from povagent.run.summary_model import RunSummary

    rows = sum(RunSummary.model_validate_json((r / "summary.json").read_text()).rows.done for r in runs)
    old = baseline_checkout(args.baseline, work / "baseline")
    print(f"{args.dataset}: {len(runs)} systems, {rows} rows ({rows / len(runs):.0f} per system; the paper: {PAPER_INSTANCES})")
    cpu: dict[str, list[float]] = {}
    agree: dict[str, bool] = {}
    for extra, what in (((), "official only"), (("diagnose", "relation"), "with diagnose + relation")):
        summaries = {}
        for k in range(args.rounds):
            order = (("before", old), ("after", None)) if k % 2 == 0 else (("after", None), ("before", old))
            for label, path in order:
                seconds, summaries[label] = rescore_cpu(runs, extra, path)
                cpu.setdefault(f"{what}/{label}", []).append(seconds)
            b, a = cpu[f"{what}/before"][-1], cpu[f"{what}/after"][-1]
            print(f"{what}, round {k + 1}: before {b:.1f} s CPU, after {a:.1f} s CPU, ratio {a / b:.2f}", flush=True)
        agree[what] = same(summaries["before"], summaries["after"])
    print(f"\nmedians of {args.rounds} rounds, CPU seconds to rescore all {rows} rows ({len(runs)} runs):")
    for what in ("official only", "with diagnose + relation"):
        b, a = statistics.median(cpu[f"{what}/before"]), statistics.median(cpu[f"{what}/after"])
        scaled = a * PAPER_INSTANCES * len(runs) / rows
        print(f"  {what:26s} before {b:6.1f} s, after {a:6.1f} s ({a / b:.2f}x; {scaled:.1f} s at {PAPER_INSTANCES} x {len(runs)}); "
              f"summaries identical to 1e-12: {agree[what]}")
    a = statistics.median(cpu["with diagnose + relation/after"]) * PAPER_INSTANCES * len(runs) / rows
    print(f"goal: under {GOAL_S:.0f} s of CPU for {PAPER_INSTANCES} x {len(runs)}: {'met' if a < GOAL_S else 'NOT met'} ({a:.1f} s)")
    print(f"load average: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
