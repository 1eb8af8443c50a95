"""The navigate task end to end: the episode offers the navigate tools (``arrived`` instead of
``answer``, no ``go_to_frame``), ``explorer-oracle`` walks the shortest path (success 100%, SPL
above 0.9), ``explorer-random`` scores below it, and ``rescore`` reproduces the run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.episode import read_record
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline
from povagent_plugins.strategies.navigate import NavigateStrategy

pytestmark = pytest.mark.timeout(300)

#: The instances every run here walks: a few keys of house 1, of every condition.
INSTANCES = {"houses": ["train_house_00001"], "sample": 6, "seed": 2}


def run_navigate(dataset: Path, folder: Path, backend: object, max_actions: int) -> Path:
    doc = {"dataset": {"path": str(dataset)}, "instances": INSTANCES, "backend": backend,
           "strategy": {"name": "navigate", "options": {"max_actions": max_actions}}, "scorers": ["navigate"],
           "output": str(folder)}  # fmt: skip
    (folder.parent / f"{folder.name}.yaml").write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(folder.parent / f"{folder.name}.yaml"))
    return folder


def overall(folder: Path) -> dict[str, float]:
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    cells = summary["metrics"]["navigate"]["overall"]
    return {name: cells[name]["value"] for name in ("success_rate", "spl")}


@pytest.fixture(scope="module")
def oracle_run(generated_release, tmp_path_factory) -> Path:
    return run_navigate(generated_release, tmp_path_factory.mktemp("navigate") / "oracle", "explorer-oracle", 16)


@pytest.fixture(scope="module")
def random_run(generated_release, tmp_path_factory) -> Path:
    backend = {"name": "explorer-random", "options": {"seed": 5}}
    return run_navigate(generated_release, tmp_path_factory.mktemp("navigate") / "random", backend, 4)


def test_an_episode_offers_the_navigate_tools_and_the_point_task_keeps_its_own():
    assert NavigateStrategy().tools().names == ("turn", "tilt", "move", "ask", "arrived")


def test_the_oracle_arrives_every_time_along_the_shortest_path(oracle_run):
    rows = read_rows(oracle_run / "results.jsonl")
    navigable = [r.scores["navigate"] for r in rows if r.scores["navigate"]["navigable"]]
    assert len(rows) == 6 and len(navigable) >= 3
    for scores in navigable:
        assert scores["success"] and scores["target_in_view"] and scores["distance_m"] <= 1.0
        assert scores["walked_m"] <= scores["shortest_m"] / 0.9
    assert all(read_record(r.exchanges[-1].raw).end == "arrived" for r in rows)
    assert overall(oracle_run)["success_rate"] == 1.0
    assert overall(oracle_run)["spl"] > 0.9


def test_an_instance_without_a_place_to_arrive_at_is_no_episode(oracle_run):
    rows = read_rows(oracle_run / "results.jsonl")
    unreachable = [r.scores["navigate"] for r in rows if not r.scores["navigate"]["navigable"]]
    assert unreachable, "the sample holds a target no reachable place within 1 m sees"
    assert all(s["answered"] is False and s["spl"] is None and not s["success"] for s in unreachable)


def test_the_random_explorer_scores_below_the_oracle(oracle_run, random_run):
    rows = read_rows(random_run / "results.jsonl")
    assert len(rows) == 6 and all(read_record(r.exchanges[-1].raw).end == "arrived" for r in rows)
    assert overall(random_run)["spl"] < overall(oracle_run)["spl"]
    assert overall(random_run)["success_rate"] < 1.0


def test_a_row_records_the_path_walked_and_rescore_reproduces_the_scores(oracle_run):
    (row, *_) = read_rows(oracle_run / "results.jsonl")
    record = read_record(row.exchanges[-1].raw)
    assert row.parse.path[0] == (record.start.x, record.start.z)
    assert row.parse.path[-1] == (row.parse.camera.x, row.parse.camera.z)
    ran = {r.key: r.model_dump(mode="json", include={"status", "parse", "scores"}) for r in read_rows(oracle_run / "results.jsonl")}
    again = rescore_run(oracle_run, "navigate")
    assert {r.key: r.model_dump(mode="json", include={"status", "parse", "scores"}) for r in read_rows(again.out_dir / "results.jsonl")} == ran
    assert json.loads((again.out_dir / "summary.json").read_text())["metrics"] == json.loads((oracle_run / "summary.json").read_text())["metrics"]


def test_a_given_walk_starts_at_the_entrance_on_the_robots_floor(oracle_run):
    given = [r for r in read_rows(oracle_run / "results.jsonl") if r.condition == "c"]
    assert given
    for row in given:
        start = read_record(row.exchanges[-1].raw).start
        assert start.y == 0.9 and start.horizon == 30.0
        assert "You start just inside the house's entrance" in row.exchanges[0].prompt


def test_a_walk_that_ends_without_arrived_fails_where_it_stopped(oracle_run, generated_release):
    from povagent.dataset.loader import load_dataset
    from povagent_plugins.scorers.navigate_scorer import NavigateScorer
    from povagent_plugins.strategies.navigate import NavigateParser

    row = next(r for r in read_rows(oracle_run / "results.jsonl") if r.scores["navigate"]["success"])
    record = read_record(row.exchanges[-1].raw)
    stopped = record.model_copy(update={"end": "no answer within 18 turns", "steps": record.steps[:-1]})
    parse = NavigateParser().parse(stopped.model_dump_json(), None)
    assert parse.answered and parse.span == "no arrival: no answer within 18 turns" and parse.path == row.parse.path
    instance = next(i for i in load_dataset(generated_release).instances() if i.id == row.instance_id)
    scores = NavigateScorer().score(instance, parse)
    assert scores["target_in_view"] and scores["distance_m"] <= 1.0  # at the right place, facing the target
    assert scores["success"] is False and scores["spl"] == 0.0


def test_text_that_is_no_episode_record_is_unparseable():
    from povagent_plugins.strategies.navigate import NavigateParser

    assert not NavigateParser().parse('{"selected_image": 0, "x": 1, "y": 2}', None).answered
