"""A run keeps what exists when it starts out of the collector's full passes, and thaws it after; it spaces the young passes out meanwhile."""

from __future__ import annotations

import gc

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.run.frozen_heap import YOUNG_THRESHOLD, frozen_heap, spaced_collections
from povagent.run.runner import run_pipeline


@pytest.fixture(autouse=True)
def _thawed():
    gc.unfreeze()  # no freeze of an earlier test's
    yield
    gc.unfreeze()


def test_a_run_freezes_the_heap_while_its_keys_run_and_thaws_it_after(write_pipeline, offline_plugin, monkeypatch):
    frozen_while_answering = []
    answer = offline_plugin.CenterBackend.complete

    async def complete(self, request, images):
        frozen_while_answering.append(gc.get_freeze_count())
        return await answer(self, request, images)

    monkeypatch.setattr(offline_plugin.CenterBackend, "complete", complete)
    result = run_pipeline(load_pipeline(write_pipeline()))
    assert result.summary.rows.done == 12
    assert min(frozen_while_answering) > 0
    assert gc.get_freeze_count() == 0


def test_a_freeze_of_the_process_own_is_left_in_place():
    gc.freeze()
    before = gc.get_freeze_count()
    # The count can only fall while this runs (a frozen object another thread frees leaves the
    # permanent generation, e.g. pytest-xdist's channel thread), never rise: the run froze
    # nothing more, so what it made inside stays out, and it left the process's freeze in place.
    with frozen_heap():
        garbage = [[] for _ in range(1000)]  # made inside: not frozen by the run
        inside = gc.get_freeze_count()
        assert 0 < inside <= before
    after = gc.get_freeze_count()
    assert 0 < after <= inside and garbage


def test_runs_inside_one_another_thaw_once_the_last_is_done():
    outer = frozen_heap()
    outer.__enter__()
    with frozen_heap():
        assert gc.get_freeze_count() > 0
    assert gc.get_freeze_count() > 0  # the outer run still runs
    outer.__exit__(None, None, None)
    assert gc.get_freeze_count() == 0


def test_a_failing_block_thaws_too():
    with pytest.raises(RuntimeError), frozen_heap():
        raise RuntimeError("a run that fails")
    assert gc.get_freeze_count() == 0


@pytest.fixture
def default_threshold():
    before = gc.get_threshold()
    gc.set_threshold(700, 10, 10)
    yield
    gc.set_threshold(*before)


def test_a_run_spaces_the_young_collections_out_while_it_runs_and_puts_the_threshold_back(write_pipeline, offline_plugin, monkeypatch, default_threshold):
    thresholds = []
    answer = offline_plugin.CenterBackend.complete

    async def complete(self, request, images):
        thresholds.append(gc.get_threshold())
        return await answer(self, request, images)

    monkeypatch.setattr(offline_plugin.CenterBackend, "complete", complete)
    run_pipeline(load_pipeline(write_pipeline()))
    assert set(thresholds) == {(YOUNG_THRESHOLD, 10, 10)}
    assert gc.get_threshold() == (700, 10, 10)


def test_spaced_collections_inside_one_another_put_the_threshold_back_once_the_last_is_done(default_threshold):
    outer = spaced_collections()
    outer.__enter__()
    with spaced_collections():
        assert gc.get_threshold()[0] == YOUNG_THRESHOLD
    assert gc.get_threshold()[0] == YOUNG_THRESHOLD  # the outer run still runs
    outer.__exit__(None, None, None)
    assert gc.get_threshold() == (700, 10, 10)


def test_a_threshold_someone_set_meanwhile_is_left_as_they_set_it(default_threshold):
    with spaced_collections():
        gc.set_threshold(5000, 20, 20)
    assert gc.get_threshold() == (5000, 20, 20)


def test_a_higher_threshold_and_a_disabled_collector_are_left_alone(default_threshold):
    gc.set_threshold(50_000, 10, 10)
    with spaced_collections():
        assert gc.get_threshold() == (50_000, 10, 10)
    gc.set_threshold(0, 10, 10)  # threshold 0: automatic collection off
    with spaced_collections():
        assert gc.get_threshold() == (0, 10, 10)
    assert gc.get_threshold() == (0, 10, 10)
