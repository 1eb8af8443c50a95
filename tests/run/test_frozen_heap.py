"""A run keeps what exists when it starts out of the collector's full passes, and thaws it after."""

from __future__ import annotations

import gc

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.run.frozen_heap import frozen_heap
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
