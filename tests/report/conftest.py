"""Fixture run and sweep folders for the report tests, scored by the real official scorer.

A simulated model answers each instance of the hand-made dataset: it selects a frame (A/B),
points near the projected GT with some noise, and fails to answer a share of instances. Rows
are written with the real ResultsWriter and scored with the real official scorer plugin, so
the report reads exactly what a run writes.
"""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest
import yaml

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.dataset.instances import row_key
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, ResultsWriter, RowStatus
from povagent.scoring.normalized_l2 import project_ground_truth
from povagent_plugins.scorers.official_scorer import OfficialScorer


def simulated_row(instance, run: int, rng: random.Random, model: str, strategy: str, answer_rate: float, noise: float) -> ResultRow:
    """One row of a simulated model on ``instance``."""
    w, h = instance.frame_size
    base = dict(
        key=row_key(instance.id, run),
        instance_id=instance.id,
        house_id=instance.house_id,
        pair_id=instance.pair_id,
        direction=str(instance.direction),
        condition=str(instance.condition),
        run=run,
        sentence=instance.sentence,
        backend="mock",
        strategy=strategy,
        parser="json",
    )
    if rng.random() > answer_rate:
        raw = "I cannot tell where that is."
        parsed = ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason="no JSON object with x and y")
        return ResultRow(
            **base,
            status=RowStatus.PARSE_ERROR,
            exchanges=[ExchangeRecord(request_hash="r", raw=raw)],
            parse=parsed,
            scores={"official": OfficialScorer().score(instance, parsed)},
        )
    k = rng.randrange(len(instance.frames)) if instance.condition.uses_exploration_frames else None
    frame = instance.frames[k or 0]
    gt = project_ground_truth(instance.target, frame.camera)
    x = min(w - 1, max(0.0, gt.u * w + rng.gauss(0, noise)))
    y = min(h - 1, max(0.0, gt.v * h + rng.gauss(0, noise)))
    answer = {"x": round(x, 1), "y": round(y, 1)} | ({"selected_image": k} if k is not None else {})
    raw = "Thinking about the observer.\n" + json.dumps(answer)
    parsed = ParsedAnswer(status=ParseStatus.OK, selected_image=k, x=round(x, 1), y=round(y, 1))
    return ResultRow(
        **base,
        status=RowStatus.ANSWERED,
        exchanges=[ExchangeRecord(request_hash="r", raw=raw)],
        parse=parsed,
        prediction=Prediction(selected_image=k, image_path=frame.image_path if k is not None else None, x=parsed.x, y=parsed.y),
        scores={"official": OfficialScorer().score(instance, parsed)},
    )


def write_run(
    folder: Path,
    dataset,
    model: str = "mock-a",
    strategy: str = "basic",
    seed: int = 0,
    runs: int = 1,
    answer_rate: float = 0.85,
    noise: float = 60.0,
) -> Path:
    """A run folder (config.yaml + results.jsonl) of a simulated model on every instance."""
    folder.mkdir(parents=True, exist_ok=True)
    config = {
        "dataset": {"path": str(Path(dataset.root).resolve())},
        "backend": {"name": "mock", "options": {"model": model}},
        "strategy": {"name": strategy},
        "parser": {"name": "json"},
        "scorers": ["official"],
        "runs": runs,
    }
    (folder / "config.yaml").write_text(yaml.safe_dump(config), encoding="utf-8")
    rng = random.Random(seed)
    with ResultsWriter(folder / "results.jsonl") as w:
        for run in range(runs):
            for inst in dataset.instances():
                w.write(simulated_row(inst, run, rng, model, strategy, answer_rate, noise))
    return folder


def write_sweep(folder: Path, dataset, cells: list[dict]) -> Path:
    """A sweep folder: one run folder per cell and ``sweep.json`` with each cell's axis values."""
    index = []
    for i, cell in enumerate(cells):
        name = f"cell_{i:02d}"
        write_run(folder / name, dataset, **cell)
        index.append({"folder": name, "axes": {"model": cell.get("model", "mock-a"), "strategy": cell.get("strategy", "basic")}})
    (folder / "sweep.json").write_text(json.dumps({"cells": index}), encoding="utf-8")
    return folder


@pytest.fixture(scope="session")
def run_dir(tmp_path_factory, mini_dataset) -> Path:
    """A single run of one simulated model, two runs per instance."""
    return write_run(tmp_path_factory.mktemp("run") / "run", mini_dataset, runs=2, seed=1)


@pytest.fixture(scope="session")
def sweep_dir(tmp_path_factory, mini_dataset) -> Path:
    """A sweep: two models x two strategies."""
    cells = [
        {"model": "mock-a", "strategy": "basic", "seed": 1, "noise": 40.0},
        {"model": "mock-a", "strategy": "cot", "seed": 2, "noise": 20.0, "answer_rate": 0.7},
        {"model": "mock-b", "strategy": "basic", "seed": 3, "noise": 90.0},
        {"model": "mock-b", "strategy": "cot", "seed": 4, "noise": 70.0, "answer_rate": 0.8},
    ]
    return write_sweep(tmp_path_factory.mktemp("sweep") / "sweep", mini_dataset, cells)


@pytest.fixture(scope="session")
def sweep_with_center(tmp_path_factory, mini_dataset) -> Path:
    """A sweep whose second cell is a center-baseline backend."""
    cells = [{"model": "mock-a", "seed": 1}, {"model": "center", "seed": 2, "noise": 0.0}]
    return write_sweep(tmp_path_factory.mktemp("sweep_center") / "sweep", mini_dataset, cells)


@pytest.fixture(scope="session")
def sweep_writer():
    """:func:`write_sweep` itself, for fixtures of any scope (a module's report built once)."""
    return write_sweep


@pytest.fixture
def make_sweep(tmp_path, mini_dataset):
    """Write a sweep of simulated cells (see :func:`write_sweep`) under ``tmp_path``."""

    def make(cells: list[dict], name: str = "sweep") -> Path:
        return write_sweep(tmp_path / name, mini_dataset, cells)

    return make


# -- a real-world set (hand-marked GT, scored by success) ------------------------------------------
REALWORLD_DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"

#: What the replayed "model" does on each demo command, per run: hit the mark, miss it in the
#: marked frame, point at the mark's spot in a frame without a mark, or give no answer.
#: Run 0: 3 hits, 5 answered; run 1: 4 hits, 5 answered (success 7/12, response 10/12).
REALWORLD_PLAN = {
    "house_1/kitchen/right/a": ("hit", "hit"),
    "house_1/kitchen/right/b": ("miss", "hit"),
    "house_1/kitchen/right/c": ("hit", "miss"),
    "house_1/bedroom/up/a": ("wrong_frame", "hit"),
    "house_1/bedroom/up/c": ("none", "hit"),
    "house_1/study/front/a": ("hit", "none"),
}


def realworld_predictions(dataset, plan: dict[str, tuple[str, ...]]) -> list[dict]:
    """Official-format prediction rows (one per instance and run, in run order) acting out
    ``plan``; points are placed on the marks through each frame's letterbox."""
    rows: list[list[dict]] = []
    for inst in dataset.instances():
        mark = inst.marks[0]
        k = next(i for i, f in enumerate(inst.frames) if f.image_path == mark.frame)
        if mark.point is not None:
            spot = mark.point
        elif mark.box is not None:
            spot = ((mark.box[0] + mark.box[2]) / 2, (mark.box[1] + mark.box[3]) / 2)
        else:
            xs, ys = zip(*mark.region)
            spot = (sum(xs) / len(xs), sum(ys) / len(ys))
        for run, what in enumerate(plan[inst.id]):
            row = {"house_id": inst.house_id, "pair_id": inst.pair_id, "direction": str(inst.direction), "type": str(inst.condition)}
            if what != "none":
                frame = (0 if k else 1) if what == "wrong_frame" else k
                x, y = (float(v) for v in inst.letterboxes[frame].to_square(spot))
                if what == "miss":
                    x, y = (5.0 if x > 256 else 506.0), (5.0 if y > 256 else 506.0)  # the far corner
                row |= {"predicted_x": round(x, 2), "predicted_y": round(y, 2), "predicted_image": inst.frames[frame].image_path}
            while len(rows) <= run:
                rows.append([])
            rows[run].append(row)
    # the replay backend gives run r the r-th row of an instance
    return [row for run_rows in rows for row in run_rows]


@pytest.fixture(scope="session")
def realworld_sweep(tmp_path_factory) -> Path:
    """A real sweep on the demo real-world set, two runs per cell: the center baseline and a
    "model" replaying :data:`REALWORLD_PLAN`; rows written and scored by the real runner."""
    from povagent.dataset.realworld_set import load_realworld
    from povagent.run.sweep import run_sweep

    base = tmp_path_factory.mktemp("realworld_sweep")
    dataset = load_realworld(REALWORLD_DEMO, cache_dir=base / "letterboxed")
    (base / "answers.json").write_text(json.dumps(realworld_predictions(dataset, REALWORLD_PLAN)), encoding="utf-8")
    (base / "pipeline.yaml").write_text(yaml.safe_dump({
        "dataset": {"path": str(REALWORLD_DEMO)},
        "backend": "center",
        "strategy": "basic",
        "parser": "json",
        "scorers": ["success"],
        "runs": 2,
        "output": str(base / "unused"),
    }))
    (base / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "pipeline.yaml",
        "output": str(base / "sweep"),
        "axes": {"backend": ["center", {"name": "replay", "options": {"path": str(base / "answers.json")}}]},
    }))
    run_sweep(base / "sweep.yaml", quiet=True)
    return base / "sweep"
