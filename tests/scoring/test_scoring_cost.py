"""Scoring cost per row (issue 28, item 4): each instance's ground truth is computed once per
dataset, not once per row, and the scores are the ones computed afresh for every row."""

from __future__ import annotations

import random

import pytest

import povagent.dataset.loader as loader
import povagent.scoring.official_release as official_release
from povagent.dataset import load_dataset
from povagent.scoring.official_release import read_release
from povagent.scoring.prediction_summary import summary_of
from povagent.scoring.predictions import score_official_rows


def random_rows(release, n: int, seed: int = 0) -> list[dict]:
    """``n`` official rows with random answers over every pair, direction, condition and frame."""
    rng = random.Random(seed)
    keys = sorted(release.pairs, key=str)
    rows = []
    for _ in range(n):
        house, pair = rng.choice(keys)
        cond = rng.choice("abc")
        row = {"house_id": house, "pair_id": pair, "direction": rng.choice(sorted(release.pairs[(house, pair)]["placements"])),
               "type": cond, "predicted_x": rng.uniform(-60, 580), "predicted_y": rng.uniform(-60, 580)}  # fmt: skip
        if cond != "c":
            row["predicted_image"] = rng.choice(sorted(release.log(house)))
        if rng.random() < 0.2:
            row["predicted_points"] = [[rng.uniform(0, 512), rng.uniform(0, 512)] for _ in range(rng.randint(1, 3))]
        rows.append(row)
    return rows


def counting(monkeypatch, module, name: str = "target_point") -> list[int]:
    """Count the calls of ``module.<name>`` (the real function still runs)."""
    calls = [0]
    real = getattr(module, name)

    def counted(*args, **kwargs):
        calls[0] += 1
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)
    return calls


@pytest.fixture(scope="module")
def rows(generated_release):
    return random_rows(read_release(generated_release), 400)


def test_official_counting_computes_each_ground_truth_once(monkeypatch, generated_release, rows):
    calls = counting(monkeypatch, official_release)
    scored, _ = score_official_rows(rows, read_release(generated_release))
    instances = {(r["house_id"], r["pair_id"], r["direction"]) for r in rows}
    assert len(scored) == len(rows) and all(s.score.answered for s in scored)
    # only instances the stage-3 judge finds appropriate need the surface rules at all
    assert 0 < calls[0] <= len(instances) < len(rows)


def test_povagent_counting_computes_each_ground_truth_once(monkeypatch, generated_release, rows):
    dataset = load_dataset(generated_release, check_images=False)
    calls = counting(monkeypatch, loader, "ground_truth_point")
    scored, _ = score_official_rows(rows, dataset)
    instances = {(r["house_id"], r["pair_id"], r["direction"]) for r in rows}
    assert sum(s.score.answered for s in scored) == len(rows)
    assert 0 < calls[0] <= len(instances) < len(rows)


@pytest.mark.parametrize("counting_", ["official", "povagent"])
def test_scores_equal_those_computed_afresh_for_every_row(generated_release, rows, counting_):
    def fresh():
        if counting_ == "official":
            return read_release(generated_release)
        return load_dataset(generated_release, check_images=False)

    shared = fresh()
    together, _ = score_official_rows(rows, shared)
    # every row against a freshly read dataset: nothing computed for another row is reused
    alone = [score_official_rows([row], fresh())[0][0] for row in rows[:120]]
    assert together[:120] == alone
    again, _ = score_official_rows(rows, shared)  # a second pass over the warm caches
    assert again == together
    assert summary_of(again) == summary_of(together)
