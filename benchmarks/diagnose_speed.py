"""What the ``diagnose`` and ``relation`` scorers cost per answer, and a paper-size rescore.

On a generated set (``--dataset``, or ``--houses``/``--seed`` to generate one), makes finished
runs of a few offline systems (planted simulations and baselines, Inferred + Stated + Given),
then measures in interleaved rounds, as CPU time of this process (``time.process_time``):

1. the scorers alone: every answered row scored by fresh ``diagnose`` and ``relation`` scorers
   (cold caches, as in one ``rescore``), per answer;
2. ``rescore_run`` of each run with and without ``--scorer diagnose --scorer relation``: the
   whole offline rescore per row, and what the two scorers add to it.

Then scales to the paper's set, 2,439 instances x 10 systems = 24,390 answers, against the goal
of 60 s of CPU. Usage::

    python benchmarks/diagnose_speed.py [--dataset PATH | --houses N --seed S] [--rounds R]
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import tempfile
import time
from pathlib import Path

from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.dataset.loader import load_dataset
from povagent.results.rows import iter_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import PipelineRun
from povagent_plugins.scorers.diagnose import DiagnoseScorer
from povagent_plugins.scorers.relation import RelationScorer

PAPER_ANSWERS = 2439 * 10
GOAL_S = 60.0
SYSTEMS = {
    "planted-ego40": {"name": "planted", "options": {"egocentric": 0.4, "pixel_sigma": 5}},
    "planted-mix": {"name": "planted", "options": {"egocentric": 0.2, "mirror": 0.2, "random_frame": 0.2, "pixel_sigma": 5}},
    "random": {"name": "random", "options": {"seed": 0}},
}


def dataset_path(args: argparse.Namespace) -> Path:
    if args.dataset:
        return Path(args.dataset)
    from povagent.generate import generate_dataset

    out = Path(tempfile.mkdtemp(prefix="diagnose_speed_")) / "POVBench"
    generate_dataset(out, houses=args.houses, seed=args.seed, frames=30, progress=False)
    return out


def make_run(dataset: Path, backend: dict, out: Path) -> Path:
    config = pipeline_from_source(ConfigSource("<speed>", {
        "dataset": {"path": str(dataset)}, "backend": backend, "strategy": "basic", "parser": "official",
        "scorers": ["official"], "cache": False, "output": str(out),
    }, {}))  # fmt: skip
    asyncio.run(PipelineRun(config).run())
    return out


def score_alone(root: Path, runs: list[Path]) -> tuple[float, int]:
    """CPU seconds to score every answered row of ``runs`` with fresh diagnose and relation
    scorers over a freshly loaded dataset (cold caches: one set per run, as one rescore has)."""
    total, n = 0.0, 0
    for run in runs:
        dataset = load_dataset(root, check_images=False)
        rows = [(dataset.instance(r.instance_id), r.parse) for r in iter_rows(run / "results.jsonl") if r.parse is not None and r.parse.answered]
        total += _score(dataset, rows)
        n += len(rows)
    return total, n


def _score(dataset, rows) -> float:
    diagnose, relation = DiagnoseScorer(), RelationScorer()
    t = time.process_time()
    for inst, parse in rows:
        diagnose.score(inst, parse, dataset)
        relation.score(inst, parse, dataset)
    return time.process_time() - t


def rescore_cpu(run: Path, extra: tuple[str, ...]) -> float:
    t = time.process_time()
    rescore_run(run, extra_scorers=extra)
    return time.process_time() - t


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset")
    parser.add_argument("--houses", type=int, default=4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    root = dataset_path(args)
    work = Path(tempfile.mkdtemp(prefix="diagnose_speed_runs_"))
    runs = [make_run(root, backend, work / name) for name, backend in SYSTEMS.items()]
    dataset = load_dataset(root, check_images=False)
    n_rows = sum(1 for run in runs for _ in iter_rows(run / "results.jsonl"))
    alone, plain, extra = [], [], []
    for _ in range(args.rounds):  # interleaved: each round measures all three
        seconds, n_answered = score_alone(root, runs)
        alone.append(seconds / n_answered)
        plain.append(sum(rescore_cpu(run, ()) for run in runs) / n_rows)
        extra.append(sum(rescore_cpu(run, ("diagnose", "relation")) for run in runs) / n_rows)
    a, p, e = statistics.median(alone), statistics.median(plain), statistics.median(extra)
    print(f"dataset {root}: {len(dataset.instances())} instances, {len(runs)} systems, {n_rows} rows, {args.rounds} rounds (medians)")
    print(f"diagnose + relation alone:           {a * 1e3:.3f} ms CPU per answer")
    print(f"rescore, official only:              {p * 1e3:.3f} ms CPU per row")
    print(f"rescore + diagnose + relation:       {e * 1e3:.3f} ms CPU per row ({e / p:.2f}x official only)")
    print(f"paper size ({PAPER_ANSWERS} answers): scorers alone {a * PAPER_ANSWERS:.1f} s, "
          f"whole rescore with them {e * PAPER_ANSWERS:.1f} s of CPU (goal {GOAL_S:.0f} s: "
          f"{'met' if e * PAPER_ANSWERS < GOAL_S else 'NOT met'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
