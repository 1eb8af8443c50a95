"""The offline baselines center, random and oracle (plugins/backends/baselines.py), on the
hand-made dataset, with the real basic strategy, json parser and official scorer."""

from __future__ import annotations

import asyncio
import dataclasses
import json

import pytest

from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.interfaces import PermanentBackendError
from povagent.plugins import get_plugin_host
from povagent_plugins.backends.baselines import CenterBaseline, OracleBaseline, RandomBaseline, instance_ordinal, seeded_rng
from povagent_plugins.strategies.basic import BasicStrategy

pytestmark = pytest.mark.timeout(60)


@pytest.fixture(scope="module")
def requests_(mini_dataset):
    """One basic-strategy request per instance of the fixture dataset."""
    store = ImageStore()
    strategy = BasicStrategy()
    return [strategy.build(i, store) for i in mini_dataset.instances()]


def answer(backend, request) -> dict:
    return json.loads(asyncio.run(backend.complete(request, ImageStore())).text)


def scored(backend, requests, dataset) -> list[dict]:
    host = get_plugin_host()
    parser, scorer = host.create("parser", "json"), host.create("scorer", "official")
    out = []
    for r in requests:
        parsed = parser.parse(asyncio.run(backend.complete(r, ImageStore())).text, r.answer)
        out.append(scorer.score(r.instance, parsed, dataset))
    return out


def ab(requests):
    return [r for r in requests if r.answer.asks_frame]


def c(requests):
    return [r for r in requests if not r.answer.asks_frame]


# -- oracle --------------------------------------------------------------------------------------
def test_oracle_error_is_about_zero_on_every_instance(requests_, mini_dataset):
    scores = scored(OracleBaseline(), requests_, mini_dataset)
    assert all(s["answered"] for s in scores)
    assert max(s["l2"] for s in scores) < 1e-3


def test_oracle_picks_the_frame_where_the_gt_is_most_central(requests_):
    from povagent.scoring.normalized_l2 import project_ground_truth

    for r in ab(requests_):
        chosen = answer(OracleBaseline(), r)["selected_image"]
        seen = [project_ground_truth(r.instance.target, f.camera) for f in r.instance.frames]
        central = [((g.u - 0.5) ** 2 + (g.v - 0.5) ** 2, i) for i, g in enumerate(seen) if g.in_frame]
        if central:
            assert chosen == min(central)[1]


def test_oracle_answers_c_without_a_frame(requests_):
    assert set(answer(OracleBaseline(), c(requests_)[0])) == {"x", "y"}


def test_oracle_without_the_instance_is_a_permanent_error(requests_):
    bare = dataclasses.replace(requests_[0], instance=None)
    with pytest.raises(PermanentBackendError, match="instance"):
        asyncio.run(OracleBaseline().complete(bare, ImageStore()))


# -- center --------------------------------------------------------------------------------------
def test_center_answers_the_image_centre(requests_):
    for r in requests_:
        got = answer(CenterBaseline(), r)
        assert (got["x"], got["y"]) == (256, 256)


def test_center_first_policy_selects_frame_zero(requests_):
    assert {answer(CenterBaseline(), r)["selected_image"] for r in ab(requests_)} == {0}


def test_center_cycle_policy_steps_through_the_frames(requests_):
    house0 = [r for r in ab(requests_) if r.instance.house_id == "train_house_00000" and r.instance.condition == "a"]
    frames = [answer(CenterBaseline(frame_policy="cycle"), r)["selected_image"] for r in house0]
    n = house0[0].answer.n_frames
    assert frames == [(instance_ordinal(r.instance)) % n for r in house0]
    assert len(set(frames)) == min(n, len(house0))


def test_center_random_policy_is_reproducible_and_in_range(requests_):
    policy = CenterBaseline(frame_policy="random", seed=3)
    first = [answer(policy, r)["selected_image"] for r in ab(requests_)]
    assert first == [answer(CenterBaseline(frame_policy="random", seed=3), r)["selected_image"] for r in ab(requests_)]
    assert all(0 <= k < r.answer.n_frames for k, r in zip(first, ab(requests_)))


def test_center_unknown_frame_policy_is_a_config_error():
    with pytest.raises(ConfigError, match=r"frame_policy.*first, random, cycle"):
        CenterBaseline(frame_policy="last")


def test_center_scores_zero_when_the_gt_is_behind_the_selected_frame(requests_, mini_dataset):
    # the official blind spot: the behind-camera GT is placed at the centre
    scores = scored(CenterBaseline(frame_policy="cycle"), ab(requests_), mini_dataset)
    behind = [s for s in scores if s["gt_behind"]]
    assert behind and all(s["l2"] == 0 and s["l2_strict"] > 1.4 for s in behind)


# -- random --------------------------------------------------------------------------------------
def test_random_is_reproducible_for_the_same_seed(requests_):
    assert [answer(RandomBaseline(seed=1), r) for r in requests_] == [answer(RandomBaseline(seed=1), r) for r in requests_]


def test_a_seeded_generator_is_random_random_of_its_seed_state_for_state():
    import hashlib
    import random

    for parts in [(0, "random", "viewspatial/7", 0), (3, "center", "h/1/left/a", 2), ()]:
        seed = int.from_bytes(hashlib.sha256("|".join(map(str, parts)).encode()).digest()[:8], "big")
        ours, theirs = seeded_rng(*parts), random.Random(seed)
        assert type(ours) is random.Random and ours.getstate() == theirs.getstate()
        assert [ours.choice("ABCD"), ours.randrange(640), ours.gauss(0, 1)] == [theirs.choice("ABCD"), theirs.randrange(640), theirs.gauss(0, 1)]


def test_random_depends_on_the_seed(requests_):
    assert [answer(RandomBaseline(seed=1), r) for r in requests_] != [answer(RandomBaseline(seed=2), r) for r in requests_]


def test_random_does_not_depend_on_request_order(requests_):
    backend = RandomBaseline(seed=5)
    forward = {r.instance.id: answer(backend, r) for r in requests_}
    backward = {r.instance.id: answer(backend, r) for r in reversed(requests_)}
    assert forward == backward


def test_random_answers_are_in_range(requests_):
    for r in requests_:
        got = answer(RandomBaseline(), r)
        assert 0 <= got["x"] <= 511 and 0 <= got["y"] <= 511
        if r.answer.asks_frame:
            assert 0 <= got["selected_image"] < r.answer.n_frames


# -- all -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("backend", [CenterBaseline(), RandomBaseline(), OracleBaseline()], ids=lambda b: b.identity()["backend"])
def test_baselines_are_not_cached(backend):
    assert backend.cacheable is False


def test_baselines_are_registered():
    assert {"center", "random", "oracle"} <= set(get_plugin_host().names("backend"))


@pytest.mark.parametrize("name", ["center", "random", "oracle"])
def test_baselines_declare_they_answer_in_process(name):
    backend = get_plugin_host().create("backend", name)
    assert backend.answers_in_process is True


@pytest.mark.parametrize("backend", [CenterBaseline(), RandomBaseline(), OracleBaseline()], ids=lambda b: b.identity()["backend"])
def test_a_baseline_answers_without_ever_suspending(backend, requests_):
    # what answers_in_process promises: the coroutine finishes at its first step, never awaiting
    for request in requests_:
        step = backend.complete(request, ImageStore())
        with pytest.raises(StopIteration) as done:
            step.send(None)
        assert done.value.value.text
