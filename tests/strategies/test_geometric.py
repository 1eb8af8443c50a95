"""The geometric strategy through the real runner: every sub-question an ordinary exchange in the
row, the worked-out answer last, resume redoing only what is missing, and every step the model
fails falling back with the row saying so.
"""

from __future__ import annotations

import asyncio
import json

import numpy as np
import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.dataset.loader import load_dataset, placement_case
from povagent.exchange.images import ImageStore
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent_plugins.backends.simulated import SimulatedPerception
from povagent_plugins.strategies.geometric import ACCOUNT_HEADER, GeometricStrategy, json_object, normalize_direction, normalize_type, parse_detections


def pipeline(tmp_path, root, backend, conditions=None, name="run", only=None):
    path = tmp_path / f"{name}.yaml"
    doc = {
        "dataset": {"path": str(root)},
        "backend": backend,
        "strategy": "geometric",
        "parser": "json",
        "concurrency": 2,
        "output": str(tmp_path / name),
        "timeout": 300,  # a loaded machine: litellm's first import alone can take tens of seconds
    }
    if conditions:
        doc["instances"] = {"conditions": conditions}
    if only:  # one instance: house/pair/direction/condition
        house, _, direction, condition = only.split("/")
        doc["instances"] = {"conditions": [condition], "directions": [direction], "houses": [house]}
    path.write_text(yaml.safe_dump(doc))
    return load_pipeline(path)


SIMULATED = {"name": "simulated", "options": {"pixel_sigma": 4.0, "seed": 1}}


def by_key(rows):
    return {r.key: r for r in rows}


def test_every_sub_question_is_an_exchange_of_the_row_and_the_worked_out_answer_is_last(tmp_path, mini_root):
    run_pipeline(pipeline(tmp_path, mini_root, SIMULATED))
    rows = by_key(read_rows(tmp_path / "run" / "results.jsonl"))
    assert len(rows) == 18 and all(r.status == "answered" for r in rows.values())
    a = rows["train_house_00001/7/left/a#0"]
    # read, surface, locate the anchor, locate the observer, then the answer
    assert len(a.exchanges) == 5
    assert json.loads(a.exchanges[0].raw) == {"observer": "Television", "anchor": "Sofa", "direction": "left"}
    assert "detections" in json.loads(a.exchanges[2].raw) and len(a.exchanges[2].image_hashes) == 2
    assert a.exchanges[0].image_hashes == [] and a.exchanges[1].image_hashes == []
    final = a.raw_response
    assert ACCOUNT_HEADER in final and "fallbacks: none" in final
    assert a.parse.span == final.splitlines()[0] and a.prediction.selected_image is not None
    c = rows["train_house_00001/7/left/c#0"]
    assert len(c.exchanges) == 4 and set(json.loads(c.raw_response.splitlines()[0])) == {"x", "y"}


def test_a_resumed_run_redoes_only_the_missing_rows_and_gets_the_same_answers(tmp_path, mini_root):
    first = run_pipeline(pipeline(tmp_path, mini_root, SIMULATED))
    results = tmp_path / "run" / "results.jsonl"
    before = by_key(read_rows(results))
    lines = results.read_text().splitlines(keepends=True)
    results.write_text("".join(lines[:7]) + lines[7][:40])  # a crash mid-row: 7 rows kept, a torn eighth
    again = run_pipeline(pipeline(tmp_path, mini_root, SIMULATED))
    after = by_key(read_rows(results))
    assert (first.n_pending, again.n_pending) == (18, 11)
    assert set(after) == set(before)
    for key, row in after.items():
        assert [e.raw for e in row.exchanges] == [e.raw for e in before[key].exchanges], key


def test_the_row_says_where_the_solver_fell_back(tmp_path, mini_root):
    # house 0's observer (a floor lamp) is listed in a frame record only where the lamp's box
    # centre is outside the image, so it is never pointed at
    run_pipeline(pipeline(tmp_path, mini_root, SIMULATED, conditions=["a"]))
    row = by_key(read_rows(tmp_path / "run" / "results.jsonl"))["train_house_00000/0/up/a#0"]
    assert "fallback: the FloorLamp was not found in any frame" in row.raw_response
    assert "fallback: observer placed at the mean position of the cameras that saw the anchor" in row.raw_response
    assert row.status == "answered"


def test_a_model_that_answers_nothing_usable_gets_the_image_centre_and_the_row_says_why(tmp_path, mini_root, povagent_host, queued_backend):
    queued_backend.queue("I am not sure what you mean.")
    run_pipeline(pipeline(tmp_path, mini_root, {"name": "queued"}, only="train_house_00001/7/left/a"))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert len(row.exchanges) == 2 and row.exchanges[0].raw == "I am not sure what you mean."
    assert "fallback: the anchor could not be read from the answer" in row.raw_response
    assert (row.prediction.selected_image, row.prediction.x, row.prediction.y) == (0, 256.0, 256.0)


def test_a_real_backend_never_sends_the_machine_readable_question(tmp_path, mini_root, loopback_server, monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test")
    loopback_server.script(
        '{"anchor": "sofa", "direction": "left"}',
        '{"surface": "floor"}',
        '{"detections": [{"image": 0, "x": 250, "y": 260, "box": [150, 200, 350, 330]}]}',
    )
    options = {"model": "openai/loopback-model", "api_base": loopback_server.url, "api_key_env": "POVAGENT_TEST_KEY"}
    run_pipeline(pipeline(tmp_path, mini_root, {"name": "litellm", "options": options}, only="train_house_00001/7/left/c"))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    bodies = [json.dumps(r.body) for r in loopback_server.requests]
    assert len(bodies) == 3  # read, surface, locate: the answer is worked out, not asked
    # the question ({"kind": "locate", "object": "Sofa", "role": "anchor", ...}) stays home
    assert all(set(r.body) == {"messages", "model", "max_tokens"} for r in loopback_server.requests)
    assert not any('"asks"' in b or '"locate"' in b or '"Sofa"' in b for b in bodies)
    assert "Find the sofa in the image" in bodies[2]
    assert row.status == "answered" and "fallbacks: none" in row.raw_response


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ('```json\n{"anchor": "Sofa"}\n```', {"anchor": "Sofa"}),
        ('I think {"a": {"b": 1}} is it', {"a": {"b": 1}}),
        ("no braces", None),
        ('{broken} then {"ok": true}', {"ok": True}),
    ],
)
def test_the_first_json_object_is_read_out_of_an_answer(text, expected):
    assert json_object(text) == expected


@pytest.mark.parametrize(("said", "known"), [("side table", "SideTable"), ("SIDE_TABLE", "SideTable"), ("couch", "Sofa"), ("kettle", "kettle"), ("", None)])
def test_furniture_names_become_known_types_where_they_can(said, known):
    assert normalize_type(said) == known


@pytest.mark.parametrize(("said", "direction"), [("Right", "right"), ("in front of", "front"), ("above", "up"), ("behind", None)])
def test_direction_words_become_the_benchmarks_four(said, direction):
    assert normalize_direction(said) == direction


def test_unusable_detections_are_dropped_and_counted():
    answer = {
        "detections": [
            {"image": 1, "x": 10, "y": 20, "box": [30, 40, 5, 6]},  # box corners put in order
            {"image": 1, "x": 11, "y": 21},  # the same frame again
            {"image": 9, "x": 1, "y": 1},  # no such frame
            {"image": 0, "box": [0, 0, 100, 50]},  # no point: the box centre
            {"image": 2},  # nothing at all
            {"image": 2, "x": 900, "y": -5},  # clamped into the image
        ]
    }
    found, dropped = parse_detections(answer, n_frames=3, width=512, height=512)
    assert dropped == 3
    assert [(d.frame, d.pixel, d.box) for d in found] == [
        (1, (10.0, 20.0), (5.0, 6.0, 30.0, 40.0)),
        (0, (50.0, 25.0), (0.0, 0.0, 100.0, 50.0)),
        (2, (511.0, 0.0), None),
    ]


def _solved(instance, root, speaker_at=None):
    """The solver's target for ``instance`` with exact perception (the simulated backend, no
    noise), and the sub-questions it asked."""
    perception = SimulatedPerception(dataset=str(root))
    asked = []

    async def ask(request):
        asked.append(dict(request.question))
        return await perception.complete(request, ImageStore())

    turns = asyncio.run(GeometricStrategy().solve(instance, ask, ImageStore(), speaker_at=speaker_at))
    return np.asarray(turns[-1][1].solved_point), asked, turns[-1][1].text


def test_where_the_speaker_stood_when_given_starts_the_directions_and_the_furniture_is_not_asked(generated_release):
    dataset = load_dataset(generated_release)
    lefts = dataset.instances(conditions=["a"], directions=["left"])[:4]
    assert lefts
    for inst in lefts:
        stood = np.asarray(inst.observer_camera.position)
        target, asked, account = _solved(inst, generated_release, speaker_at=stood)
        assert not any(q.get("role") == "observer" for q in asked), inst.id
        assert "where the speaker stood, given" in account
        assert np.linalg.norm(target - np.asarray(inst.target)) < 0.02, inst.id
        # a speaker facing the anchor from the other side has its left where this one has its right
        anchor = np.asarray(inst.anchor_object.position.as_tuple())
        across, _, _ = _solved(inst, generated_release, speaker_at=2 * anchor - stood)
        case = placement_case(dataset.houses[inst.house_id].pairs[inst.pair_id], "left")
        assert np.linalg.norm(across - case.target(direction="right")) < 0.02, inst.id
        assert np.linalg.norm(across - np.asarray(inst.target)) > 0.1, inst.id
