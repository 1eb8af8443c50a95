"""The relation task: each generated instance asked "where is the X relative to the Y?" over
the registry's directions, worded per condition without giving the direction away."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.config.models import PipelineConfig, TaskSpec
from povagent.config.pipeline import load_pipeline
from povagent.dataset.loader import load_dataset
from povagent.errors import ConfigError, DatasetError
from povagent.geometry.directions import DIRECTION_REGISTRY, spec_of
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline
from povagent.tasks.relation import GIVEN_VIEW
from povagent.tasks.task_set import for_task


@pytest.fixture(scope="module")
def relation_set(generated_release):
    point = load_dataset(generated_release, check_images=False)
    return point, for_task(point, TaskSpec(name="relation"))


def test_a_point_instance_whose_target_a_frame_shows_becomes_a_relation_instance_with_its_id(relation_set):
    point, relation = relation_set
    ids = [i.id for i in relation.instances()]
    assert set(ids) <= {i.id for i in point.instances()} and len(ids) >= 0.8 * len(point.instances())
    assert {i.condition.value for i in relation.instances()} == {"a", "b", "c"}


def test_the_question_says_where_the_target_is_in_the_frame_it_names(relation_set):
    _, relation = relation_set
    for inst in relation.instances():
        found = re.search(r"In (?:Image (\d+)|the image), the (.+?) is at pixel \((\d+), (\d+)\)\.", inst.question.question)
        assert found, inst.question.question
        frame = inst.frames[int(found[1])] if found[1] else inst.frames[0]
        assert (found[1] is None) == (inst.condition.value == "c")
        u, v, depth = frame.camera.project_point(inst.target)
        assert depth > 0 and (int(found[3]), int(found[4])) == (int(u * frame.camera.width), int(v * frame.camera.height))


def test_the_question_never_words_the_direction(relation_set):
    _, relation = relation_set
    for inst in relation.instances():
        spec = spec_of(inst.direction)
        phrases = [p.split("{anchor}")[0].strip() for p in (spec.sentence_phrase, spec.on_anchor_phrase, spec.seat_phrase) if p]
        text = inst.question.question
        assert not any(p in text for p in phrases if p != "on the"), (inst.id, text)
        assert spec.short_words not in text and inst.sentence == text


def test_the_options_are_the_registry_directions_and_the_gold_is_the_instances_direction(relation_set):
    _, relation = relation_set
    for inst in relation.instances():
        q = inst.question
        assert sorted(text for _, text in q.options) == sorted(s.short_words for s in DIRECTION_REGISTRY)
        assert dict(q.options)[q.gold] == spec_of(inst.direction).short_words
        assert q.category == str(inst.direction) and q.profile == "plain"


def test_the_options_are_shuffled_per_instance_and_the_same_on_every_load(relation_set, generated_release):
    _, relation = relation_set
    again = for_task(load_dataset(generated_release, check_images=False), TaskSpec(name="relation"))
    orders = [i.question.options for i in relation.instances()]
    assert orders == [i.question.options for i in again.instances()]
    assert len(set(orders)) > 1 and len({i.question.gold for i in relation.instances()}) > 1


def test_each_condition_words_the_question_as_its_sentence_does(relation_set):
    point, relation = relation_set
    for inst in relation.instances():
        source = point.instance(inst.id).sentence
        if inst.condition.value == "c":
            assert inst.question.question.startswith(GIVEN_VIEW)
        else:  # the A/B sentence up to its relation: the activity (B: naming the observer)
            context = inst.question.question.split(". In Image ", 1)[0]
            assert source.startswith(context) and len(context) > 10
        assert inst.question.question.endswith("?")


def test_the_oracle_answers_every_relation_question_correctly(task_pipeline, run_rows):
    rows = run_rows(task_pipeline("relation", "oracle"))
    assert rows and all(r["scores"]["choice"]["correct"] for r in rows)


def test_random_answers_are_right_about_one_time_in_n(task_pipeline, run_rows):
    rows = run_rows(task_pipeline("relation", "random"))
    n, hits = len(rows), sum(r["scores"]["choice"]["correct"] for r in rows)
    p = 1 / len(DIRECTION_REGISTRY)
    half_width = 1.96 * math.sqrt(p * (1 - p) / n)  # the Wald interval around 1/N
    assert abs(hits / n - p) <= half_width, (hits, n)


def _config(**task) -> PipelineConfig:
    return PipelineConfig.model_validate({"dataset": "x", "backend": {"name": "oracle"}, "output": "out", **task})


def test_the_task_is_in_the_config_hash_and_the_point_task_leaves_it_as_it_was():
    assert _config(task="relation").config_hash() != _config().config_hash()
    assert _config(task="point").config_hash() == _config().config_hash()
    assert "task" not in _config().resolved_dict() and _config(task="relation").resolved_dict()["task"]["name"] == "relation"


def test_an_unknown_task_is_refused_in_one_line(task_pipeline):
    with pytest.raises(ConfigError) as refused:
        load_pipeline(task_pipeline("navigation-by-smell"))
    named = [line for line in str(refused.value).splitlines() if "navigation-by-smell" in line]
    assert len(named) == 1 and "line 3: task: unknown task 'navigation-by-smell': one of point, relation, multi-hop" in named[0]


def test_a_relation_pipeline_asking_for_a_point_is_refused_naming_the_strategy(task_pipeline):
    with pytest.raises(ConfigError, match=r"line 6: task relation is answered as a choice, and strategy 'basic' asks for a point"):
        load_pipeline(task_pipeline("relation", strategy="basic", scorers=["official"]))


def test_a_set_whose_sentences_the_generator_did_not_write_is_refused_naming_the_field(dataset_copy):
    house = dataset_copy / "artifacts" / "train_house_00000" / "train_house_00000.json"
    pairs = json.loads(house.read_text())
    direction = next(iter(pairs[0]["stage5"]))
    pairs[0]["stage5"][direction]["type_a"] = "Someone left a book somewhere near the bed."
    house.write_text(json.dumps(pairs))
    relation = for_task(load_dataset(dataset_copy, check_images=False), TaskSpec(name="relation"))
    with pytest.raises(DatasetError, match=rf"train_house_00000\.json: pair \S+ field stage5\.{direction}\.type_a: .*povagent generate"):
        relation.instances(conditions=["a"])


def test_rescore_reads_a_relation_run_through_its_task(task_pipeline, run_rows):
    pipeline = task_pipeline("relation", "oracle", instances={"conditions": ["c"]})
    rows = run_rows(pipeline)
    result = rescore_run(Path(yaml.safe_load(pipeline.read_text())["output"]), "choice")
    rescored = [json.loads(line) for line in (result.out_dir / "results.jsonl").read_text().splitlines()]
    assert not result.warnings and len(rescored) == len(rows)
    assert all(r["scores"]["choice"]["correct"] for r in rescored)


def test_show_prompt_shows_the_relation_question(task_pipeline, relation_set, tmp_path):
    _, relation = relation_set
    inst = next(i for i in relation.instances() if i.condition.value == "c")
    result = CliRunner().invoke(app, ["show-prompt", str(task_pipeline("relation")), "--instance", inst.id, "--out", str(tmp_path / "shown")])
    assert result.exit_code == 0, result.output
    assert inst.question.question in result.output and inst.question.options_block() in result.output


def test_a_run_handed_a_loaded_set_asks_it_the_pipelines_task(task_pipeline, relation_set):
    point, _ = relation_set
    result = run_pipeline(load_pipeline(task_pipeline("relation", instances={"conditions": ["c"], "limit": 4})), dataset=point)
    rows = [json.loads(line) for line in (result.run_dir / "results.jsonl").read_text().splitlines()]
    assert len(rows) == 4 and all(r["scores"]["choice"]["correct"] for r in rows)
