"""Do the diagnostics recover planted behaviour? The worked example of docs/how-to/why-models-fail.md.

Runs ``planted`` simulations (a behaviour simulation, not a model) with known shares, and two
baselines for scale, over a generated set (default: 10 houses, seed 0, 30 frames), scored with
``official``, ``diagnose`` and ``relation``, and prints per system and condition: the official
mean L2, the first failing step's shares, the egocentric-bias index with its 95% CI and the
answers it counts, what the planted backend actually drew (``d.ego``: the egocentric share
among the answers the index counts, what it should recover; ``d.rf``: the random-frame share of
all answers, what the frame step should recover), and the relation success. Usage::

    python benchmarks/planted_recovery.py [--dataset PATH | --houses N --seed S] [--runs R]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from diagnose_thresholds import dataset_path

from povagent.config.pipeline import pipeline_from_source
from povagent.config.yaml_reader import ConfigSource
from povagent.dataset.loader import load_dataset
from povagent.results.rows import iter_rows
from povagent.run.runner import PipelineRun
from povagent.scoring.diagnosis import STEPS
from povagent_plugins.backends.planted import PlantedBehaviour

SYSTEMS: dict[str, dict[str, Any]] = {
    "planted truth": {"name": "planted", "options": {"pixel_sigma": 5, "seed": 0}},
    "planted egocentric 0.4": {"name": "planted", "options": {"egocentric": 0.4, "pixel_sigma": 5, "seed": 0}},
    "planted mirror 0.3": {"name": "planted", "options": {"mirror": 0.3, "pixel_sigma": 5, "seed": 0}},
    "planted random frame 0.3": {"name": "planted", "options": {"random_frame": 0.3, "pixel_sigma": 5, "seed": 0}},
    "planted mix .2/.1/.1": {"name": "planted", "options": {"egocentric": 0.2, "mirror": 0.1, "random_frame": 0.1, "pixel_sigma": 5, "seed": 0}},
    "center (random frame)": {"name": "center", "options": {"frame_policy": "random", "seed": 0}},
    "random": {"name": "random", "options": {"seed": 0}},
}


def run(dataset: Path, backend: dict[str, Any], out: Path, runs: int) -> dict[str, Any]:
    config = pipeline_from_source(ConfigSource("<recovery>", {
        "dataset": {"path": str(dataset)}, "backend": backend, "strategy": "basic", "parser": "official",
        "scorers": ["official", "diagnose", "relation"], "runs": runs, "cache": False, "output": str(out),
    }, {}))  # fmt: skip
    asyncio.run(PipelineRun(config).run())
    return json.loads((out / "summary.json").read_text())  # the summary as its file holds it


def drawn(out: Path, backend: dict[str, Any], dataset) -> dict[str, tuple[float | None, float]]:
    """Per condition, what the planted backend drew: the egocentric share among the answers
    that cast a bias vote (what the index should recover), and the random-frame share of all
    answers (what the frame step should recover)."""
    if backend["name"] != "planted":
        return {}
    planted = PlantedBehaviour(**backend["options"])
    votes: dict[str, list[bool]] = {}
    frames: dict[str, list[bool]] = {}
    for r in iter_rows(out / "results.jsonl"):
        behaviour = planted.behaviour(dataset.instance(r.instance_id), r.run)
        frames.setdefault(r.condition, []).append(behaviour == "random_frame")
        if r.scores.get("diagnose", {}).get("bias_eligible"):
            votes.setdefault(r.condition, []).append(behaviour == "egocentric")
    return {c: (sum(votes[c]) / len(votes[c]) if votes.get(c) else None, sum(f) / len(f)) for c, f in frames.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset")
    parser.add_argument("--houses", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=1)
    args = parser.parse_args()
    root = dataset_path(args, "planted_recovery_")
    dataset = load_dataset(root, check_images=False)
    work = Path(tempfile.mkdtemp(prefix="planted_recovery_runs_"))
    print(f"dataset {root}: {len(dataset.houses)} houses, {len(dataset.instances(conditions=['a']))} instances per condition, "
          f"{args.runs} run(s)\n")
    head = f"{'system':<25} {'cond':<4} {'L2':>6} " + " ".join(f"{s[:9]:>9}" for s in STEPS)
    print(head + f" {'ego bias [95% CI]':>19} {'n':>4} {'d.ego':>6} {'d.rf':>6} {'relation':>8}")
    for i, (name, backend) in enumerate(SYSTEMS.items()):
        out = work / f"system{i}"
        summary = run(root, backend, out, args.runs)
        planted = drawn(out, backend, dataset)
        for cond, cell in summary["diagnostics"]["per_condition"].items():
            steps = " ".join(f"{100 * (cell['failure_steps'][s] or 0):8.1f}%" for s in STEPS)
            bias = cell["egocentric_bias"]
            ci = cell["egocentric_bias_ci"]
            bias_text = "-" if bias is None else f"{bias:.2f} [{ci[0]:.2f}, {ci[1]:.2f}]"
            ego, rf = planted.get(cond, (None, None))
            print(f"{name:<25} {cond:<4} {summary['per_condition'][cond]['mean_l2']:6.3f} {steps} {bias_text:>19} "
                  f"{cell['bias_n']:4d} {'-' if ego is None else f'{ego:.2f}':>6} {'-' if rf is None else f'{rf:.2f}':>6} "
                  f"{100 * cell['relation_success']:7.1f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
