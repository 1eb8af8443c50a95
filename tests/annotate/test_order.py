"""The annotator's order: seeded per annotator, the same on resume, pairs never back to back."""

from __future__ import annotations

import itertools

from povagent.annotate.order import annotator_order, pair_of


def keys_of(dataset):
    return [(i, 0) for i in dataset.instances()]


def ids(keys):
    return [(i.id, r) for i, r in keys]


def test_the_same_annotator_and_seed_give_the_same_order_whatever_order_keys_come_in(mini_dataset):
    keys = keys_of(mini_dataset)
    assert ids(annotator_order(keys, "alice", 3)) == ids(annotator_order(list(reversed(keys)), "alice", 3))


def test_two_annotators_see_different_orders(mini_dataset):
    keys = keys_of(mini_dataset)
    assert ids(annotator_order(keys, "alice")) != ids(annotator_order(keys, "bob"))


def test_the_order_is_a_shuffle_not_the_dataset_order(mini_dataset):
    keys = keys_of(mini_dataset)
    assert ids(annotator_order(keys, "alice", pairs_apart=False)) != ids(keys)
    assert sorted(ids(annotator_order(keys, "alice"))) == sorted(ids(keys))


def test_no_two_neighbours_share_a_pair_when_the_set_allows_it(tmp_path):
    from povagent.dataset import load_dataset
    from povagent.testing.pytest_plugin import write_release

    keys = keys_of(load_dataset(write_release(tmp_path / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)))
    pairs = [pair_of(k) for k in keys]
    assert len(set(pairs)) > 1 and max(pairs.count(p) for p in set(pairs)) * 2 <= len(pairs) + 1, "the release must allow spacing"
    for name in ("alice", "bob", "carol", "dave"):
        order = [pair_of(k) for k in annotator_order(keys, name)]
        assert all(a != b for a, b in itertools.pairwise(order)), name


def test_a_pair_holding_most_of_the_set_follows_itself_no_more_than_it_must(mini_dataset):
    keys = keys_of(mini_dataset)
    pairs = [pair_of(k) for k in keys]
    most = max(pairs.count(p) for p in set(pairs))
    unavoidable = max(0, 2 * most - len(pairs) - 1)
    assert unavoidable > 0, "the hand-made set has one crowded pair"
    for name in ("alice", "bob"):
        order = [pair_of(k) for k in annotator_order(keys, name)]
        assert sum(a == b for a, b in itertools.pairwise(order)) == unavoidable, name


def test_pairs_may_follow_each_other_when_asked(mini_dataset):
    keys = keys_of(mini_dataset)
    adjacent = 0
    for seed in range(20):
        order = [pair_of(k) for k in annotator_order(keys, "alice", seed, pairs_apart=False)]
        adjacent += sum(a == b for a, b in itertools.pairwise(order))
    assert adjacent > 0
