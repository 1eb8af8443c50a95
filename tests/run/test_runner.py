"""The runner: rows, resume, retries, caching, redaction and observers, on a small synthetic release."""

from __future__ import annotations

import asyncio
import json
import time
from collections import Counter

import pytest

from povagent import hookimpl
from povagent.config.pipeline import load_pipeline
from povagent.engine.retry import error_type_of, is_transient
from povagent.errors import ConfigError
from povagent.interfaces import PermanentBackendError, TransientBackendError
from povagent.results.rows import read_rows
from povagent.results.upgrade import SUMMARY_FORMAT
from povagent.run.runner import run_pipeline

N_KEYS = 12  # 4 (pair, direction)s x 3 conditions in the small release


def run(path, **kw):
    return run_pipeline(load_pipeline(path), **kw)


def rows_of(result):
    return read_rows(result.run_dir / "results.jsonl")


def test_run_writes_the_run_folder_with_one_row_per_key(write_pipeline):
    result = run(write_pipeline(runs=2))
    for name in ("config.yaml", "results.jsonl", "log.jsonl", "summary.json"):
        assert (result.run_dir / name).is_file(), name
    keys = [r.key for r in rows_of(result)]
    assert len(keys) == len(set(keys)) == 2 * N_KEYS
    summary = json.loads((result.run_dir / "summary.json").read_text())
    assert summary["rows"]["answered"] == 2 * N_KEYS and summary["complete"] is True
    assert summary["overall"]["response_rate"] == 1.0 and set(summary["per_run"]) == {"0", "1"}


def test_answered_rows_carry_prediction_and_official_score(write_pipeline):
    rows = rows_of(run(write_pipeline(instances={"conditions": ["a"], "limit": 1})))
    (row,) = rows
    assert row.status == "answered" and row.prediction.image_path == "exploration_images/frame_000.png"
    assert row.scores["official"]["answered"] is True and row.scores["official"]["l2"] is not None
    assert row.exchanges[0].image_hashes and row.prompt_tokens == 100


def test_resume_runs_only_the_missing_keys(write_pipeline, offline_plugin):
    run(write_pipeline(instances={"limit": 5}))
    assert offline_plugin.CALLS["count"] == 5
    result = run(write_pipeline())
    assert offline_plugin.CALLS["count"] == N_KEYS
    assert result.n_pending == N_KEYS - 5
    keys = [r.key for r in rows_of(result)]
    assert len(keys) == len(set(keys)) == N_KEYS


def test_unparseable_answer_is_a_parse_error_and_not_scored(write_pipeline):
    rows = rows_of(run(write_pipeline(backend={"name": "test-center", "options": {"reply": "I cannot tell."}})))
    assert {r.status for r in rows} == {"parse_error"}
    assert all(r.scores == {} and r.raw_response == "I cannot tell." for r in rows)


def test_parse_errors_count_against_the_response_rate(write_pipeline):
    result = run(write_pipeline(backend={"name": "test-center", "options": {"reply": "no idea"}}))
    assert result.summary.overall.response_rate == 0.0 and result.summary.overall.mean_l2 is None


def test_transient_failures_are_retried_then_answered(write_pipeline, offline_plugin):
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": [503, "connection"]}}, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert row.status == "answered" and row.retries == 2 and result.stats.requests == 3


def test_timeout_is_transient(write_pipeline):
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": ["timeout"]}}, timeout=0.05, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert row.status == "answered" and row.retries == 1


def test_retry_after_is_honoured(write_pipeline):
    path = write_pipeline(backend={"name": "test-flaky", "options": {"script": [429], "retry_after": 0.3}}, instances={"limit": 1})
    t0 = time.perf_counter()
    (row,) = rows_of(run(path))
    assert time.perf_counter() - t0 >= 0.3
    assert row.status == "answered" and row.retries == 1


def test_permanent_error_is_not_retried_and_is_an_infra_error(write_pipeline):
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": [401]}}, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert result.stats.requests == 1
    assert row.status == "infra_error" and row.error_type == "auth" and row.scores == {}


def test_exhausted_retries_are_an_infra_error_never_scored(write_pipeline):
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": [503, 503, 503]}}, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert result.stats.requests == 3  # retry.attempts in the test pipeline
    assert row.status == "infra_error" and row.error_type == "server_error" and "after 3 attempts" in row.error_message
    assert result.summary.overall.response_rate == 0.0


def test_backend_bug_is_recorded_not_retried(write_pipeline):
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": ["crash"]}}, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert result.stats.requests == 1 and row.error_type == "backend_exception"
    assert "bug in backend" in (result.run_dir / "log.jsonl").read_text()


class _Status(Exception):
    def __init__(self, status_code):
        self.status_code = status_code


@pytest.mark.parametrize(
    "exc, transient",
    [
        (TransientBackendError("x", status=503), True),
        (TimeoutError(), True),
        (TimeoutError(), True),
        (ConnectionResetError(), True),
        (OSError("network unreachable"), True),
        (_Status(429), True),
        (_Status(502), True),
        (PermanentBackendError("bad request", status=400), False),
        (PermanentBackendError("unauthorised", status=401), False),
        (_Status(400), False),
        (_Status(403), False),
        (FileNotFoundError("x.png"), False),
        (ValueError("bug"), False),
    ],
)
def test_retry_classification(exc, transient):
    assert is_transient(exc) is transient


def test_error_types_name_the_failure():
    assert error_type_of(TransientBackendError("x", status=429)) == "rate_limited"
    assert error_type_of(TimeoutError()) == "timeout"
    assert error_type_of(PermanentBackendError("x", status=400)) == "bad_request"
    assert error_type_of(ConnectionRefusedError()) == "connection"


def test_cache_hit_makes_no_call(write_pipeline, offline_plugin, tmp_path):
    cache = str(tmp_path / "shared-cache.sqlite")
    run(write_pipeline(cache=cache))
    assert offline_plugin.CALLS["count"] == N_KEYS
    result = run(write_pipeline(cache=cache, output=str(tmp_path / "second")))
    assert offline_plugin.CALLS["count"] == N_KEYS
    assert result.stats.cache_hits == N_KEYS and result.stats.requests == 0
    assert all(r.exchanges[0].cached for r in rows_of(result))


def test_cache_key_includes_the_run_index(write_pipeline, offline_plugin, tmp_path):
    cache = str(tmp_path / "shared-cache.sqlite")
    run(write_pipeline(cache=cache, runs=[0]))
    run(write_pipeline(cache=cache, runs=[0, 1], output=str(tmp_path / "more")))
    assert offline_plugin.CALLS["count"] == 2 * N_KEYS


def test_errors_are_not_cached(write_pipeline, offline_plugin, tmp_path):
    cache = str(tmp_path / "shared-cache.sqlite")
    first = run(write_pipeline(cache=cache, backend={"name": "test-flaky", "options": {"script": [401]}}, instances={"limit": 1}))
    assert rows_of(first)[0].status == "infra_error"
    second = run(write_pipeline(cache=cache, backend={"name": "test-flaky"}, instances={"limit": 1}, output=str(tmp_path / "again")))
    assert second.stats.cache_hits == 0 and rows_of(second)[0].status == "answered"


def test_uncacheable_backend_skips_the_cache(write_pipeline, offline_plugin, tmp_path):
    cache = tmp_path / "c.sqlite"
    backend = {"name": "test-center", "options": {"cacheable": False}}
    run(write_pipeline(cache=str(cache), backend=backend))
    run(write_pipeline(cache=str(cache), backend=backend, output=str(tmp_path / "b")))
    assert offline_plugin.CALLS["count"] == 2 * N_KEYS


def test_secrets_are_redacted_from_rows_and_logs(write_pipeline, monkeypatch):
    monkeypatch.setenv("DEMO_API_KEY", "sk-live-abcdefgh12345678")
    result = run(write_pipeline(backend={"name": "test-flaky", "options": {"script": [401]}}, instances={"limit": 1}))
    (row,) = rows_of(result)
    assert "[REDACTED]" in row.error_message
    for name in ("results.jsonl", "log.jsonl", "summary.json", "config.yaml"):
        assert "abcdefgh12345678" not in (result.run_dir / name).read_text(), name


def test_concurrency_bounds_requests_in_flight(write_pipeline, povagent_host):
    from povagent.exchange.messages import Response
    from povagent.interfaces import Backend

    state = {"now": 0, "peak": 0}

    class Counting(Backend):
        cacheable = False

        def __init__(self, **_):
            pass

        def identity(self):
            return {"backend": "counting"}

        async def complete(self, request, images):
            state["now"] += 1
            state["peak"] = max(state["peak"], state["now"])
            await asyncio.sleep(0.01)
            state["now"] -= 1
            return Response(text='{"selected_image": 0, "x": 1, "y": 1}' if request.answer.asks_frame else '{"x": 1, "y": 1}')

    class Plugin:
        @hookimpl
        def register_backends(self, register):
            register("counting", Counting)

    povagent_host.add_plugin(Plugin(), name="counting")
    try:
        run(write_pipeline(backend="counting", concurrency=3, runs=2))
    finally:
        povagent_host.remove_plugin("counting")
    assert state["peak"] == 3


def test_resume_into_a_folder_of_another_pipeline_is_refused(write_pipeline):
    run(write_pipeline(instances={"limit": 1}))
    with pytest.raises(ConfigError, match=r"holds rows of a different pipeline"):
        run(write_pipeline(backend={"name": "test-center", "options": {"reply": "other"}}))


def test_a_resumed_run_tries_failed_keys_again_without_duplicates(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", instances={"limit": 3}, concurrency=1)
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", 400, 400]
    first = run(path)
    assert Counter(r.status for r in rows_of(first)) == {"infra_error": 2, "answered": 1}
    assert first.exit_code == 3 and first.n_failed == 2
    second = run(path)  # the same command again, nothing else: the failed keys run again
    rows = [json.loads(line) for line in (second.run_dir / "results.jsonl").read_text().splitlines()]
    assert len(rows) == len({r["key"] for r in rows}) == 3
    assert {r["status"] for r in rows} == {"answered"} and second.n_pending == 2 and second.exit_code == 0


def test_keep_errors_leaves_failed_keys_as_they_are(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", instances={"limit": 3}, concurrency=1)
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", 400, 400]
    run(path)
    calls = offline_plugin.CALLS["count"]
    kept = run(path, retry_failed=False)
    assert offline_plugin.CALLS["count"] == calls and kept.n_pending == 0
    assert Counter(r.status for r in rows_of(kept)) == {"infra_error": 2, "answered": 1} and kept.exit_code == 3


def test_parse_errors_are_answers_and_are_not_run_again(write_pipeline, offline_plugin):
    path = write_pipeline(backend={"name": "test-center", "options": {"reply": "no point here"}}, instances={"limit": 2})
    first = run(path)
    assert {r.status for r in rows_of(first)} == {"parse_error"} and first.exit_code == 0
    calls = offline_plugin.CALLS["count"]
    assert run(path).n_pending == 0 and offline_plugin.CALLS["count"] == calls


@pytest.mark.parametrize("failure", [401, 404, "connection"])
def test_the_first_key_failing_for_good_stops_the_run_before_it_fans_out(write_pipeline, offline_plugin, failure):
    path = write_pipeline(backend="test-flaky", retry={"attempts": 2, "initial_wait": 0.0, "max_wait": 0.0})
    tries = 2 if failure == "connection" else 1  # a transient failure is retried before it counts
    offline_plugin.FlakyBackend.SCRIPT[:] = [failure] * tries
    result = run(path)
    assert result.stopped is not None and "nothing else was sent" in result.stopped
    assert "test-center" in result.stopped  # the model is named
    assert len(rows_of(result)) == 1 and result.n_missing == N_KEYS - 1 and result.exit_code == 4
    assert offline_plugin.CALLS["count"] == tries
    resumed = run(path)  # fixed: the same command finishes the run, no duplicate row
    keys = [r.key for r in rows_of(resumed)]
    assert len(keys) == len(set(keys)) == N_KEYS and resumed.exit_code == 0


def test_a_first_key_failing_for_a_passing_reason_does_not_stop_the_run(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", retry={"attempts": 1})
    offline_plugin.FlakyBackend.SCRIPT[:] = [503]
    result = run(path)
    assert result.stopped is None and result.n_failed == 1 and result.n_missing == 0 and result.exit_code == 3


def test_failures_in_a_row_trip_the_circuit_breaker(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", concurrency=1, stop_after_failures=3, retry={"attempts": 1})
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", 503, "ok", 503, 503, 503, 503, 503]
    result = run(path)
    statuses = [r.status for r in rows_of(result)]
    # an answer resets the count: the breaker trips at the third failure in a row, not the fourth overall
    assert statuses == ["answered", "infra_error", "answered", "infra_error", "infra_error", "infra_error"]
    assert result.stopped is not None and "3 keys in a row failed" in result.stopped and result.exit_code == 4
    assert result.n_missing == N_KEYS - 6


def test_no_circuit_breaker_when_stop_after_failures_is_zero(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", concurrency=1, stop_after_failures=0, retry={"attempts": 1})
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok"] + [503] * (N_KEYS - 1)
    result = run(path)
    assert result.stopped is None and result.n_failed == N_KEYS - 1 and result.exit_code == 3


def test_an_infra_error_row_counts_the_retries_it_spent(write_pipeline, offline_plugin):
    path = write_pipeline(backend="test-flaky", instances={"limit": 2}, concurrency=1,
                          retry={"attempts": 3, "initial_wait": 0.0, "max_wait": 0.0})  # fmt: skip
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", 503, 503, 503]
    result = run(path)
    failed = [r for r in rows_of(result) if r.status == "infra_error"]
    assert [r.retries for r in failed] == [2] and result.summary.usage.retries == 2


def test_lifecycle_hooks_observe_the_run(write_pipeline, povagent_host):
    events = []

    class Observer:
        @hookimpl
        def povagent_run_start(self, run_dir, config, n_pending, n_total):
            events.append(("start", n_pending, n_total))

        @hookimpl
        def povagent_instance_done(self, run_dir, row):
            assert (row.key + '"') in open(f"{run_dir}/results.jsonl").read()  # durable before reported
            events.append(("done", row.key))

        @hookimpl
        def povagent_run_end(self, run_dir, summary):
            events.append(("end", summary["rows"]["done"], summary["format_version"]))  # what summary.json holds

    povagent_host.add_plugin(Observer(), name="observer")
    try:
        run(write_pipeline())
    finally:
        povagent_host.remove_plugin("observer")
    assert events[0] == ("start", N_KEYS, N_KEYS) and events[-1] == ("end", N_KEYS, SUMMARY_FORMAT)
    assert len([e for e in events if e[0] == "done"]) == N_KEYS


def test_observer_that_raises_does_not_stop_the_run(write_pipeline, povagent_host, capsys):
    class Broken:
        @hookimpl
        def povagent_instance_done(self, run_dir, row):
            raise RuntimeError("dashboard down")

    povagent_host.add_plugin(Broken(), name="broken-observer")
    try:
        result = run(write_pipeline())
    finally:
        povagent_host.remove_plugin("broken-observer")
    assert result.summary.rows.answered == N_KEYS
    assert "dashboard down" in capsys.readouterr().err


def test_sample_is_seeded_and_kept_in_dataset_order(write_pipeline, small_release):
    from povagent.dataset import load_dataset
    from povagent.run.pending import select_instances

    ds = load_dataset(small_release)
    a = select_instances(ds, load_pipeline(write_pipeline(instances={"sample": 5, "seed": 3})))
    b = select_instances(ds, load_pipeline(write_pipeline(instances={"sample": 5, "seed": 3}, output="elsewhere")))
    order = [i.id for i in ds.instances()]
    assert [i.id for i in a] == [i.id for i in b] and len(a) == 5
    assert [order.index(i.id) for i in a] == sorted(order.index(i.id) for i in a)


def test_the_image_store_keeps_the_houses_in_flight_not_every_house_seen(write_pipeline, small_release):
    from povagent.dataset import load_dataset
    from povagent.exchange.images import ImageStore

    instances = load_dataset(small_release).instances()
    house_of = {f.file: inst.house_id for inst in instances for f in inst.frames}
    cached_houses: list[set[str]] = []

    class Watched(ImageStore):
        def data_url(self, image_hash: str) -> str:
            cached = {self.info(k[0]).image_hash for k in self._cache}
            cached_houses.append({house_of[p] for p, info in self._by_path.items() if info.image_hash in cached})
            return super().data_url(image_hash)

    images = Watched()
    result = run(write_pipeline(backend={"name": "test-center", "options": {"encode": True}}, concurrency=1), images=images)
    assert result.summary.rows.answered == N_KEYS
    assert len({i.house_id for i in instances}) == 2 and {h for c in cached_houses for h in c} == set(house_of.values())
    # one house at a time: the first house's frames are let go before the second's are read
    assert max(len(c) for c in cached_houses) == 1
    assert images.cached_bytes == 0  # and nothing is kept once the run is over
    assert images.stats.rebuilds == 0 and images.stats.file_reads == len(house_of)


def test_a_second_run_on_the_same_store_reads_the_let_go_frames_again_off_the_event_loop(write_pipeline):
    import threading

    from povagent.exchange.images import ImageStore

    readers: list[str] = []

    class Watched(ImageStore):
        def _read_file(self, path, size=None):
            readers.append(threading.current_thread().name)
            return super()._read_file(path, size)

    images = Watched()
    backend = {"name": "test-center", "options": {"encode": True}}
    run(write_pipeline(backend=backend), images=images)
    first = len(readers)
    again = run(write_pipeline("again.yaml", backend=backend, output=str(write_pipeline().parent / "again")), images=images)
    assert again.summary.rows.answered == N_KEYS
    assert len(readers) == 2 * first and images.stats.rebuilds == first  # every frame once more, as a rebuild
    assert threading.main_thread().name not in readers  # never on the event loop's thread


def test_a_frame_swapped_for_a_link_between_runs_on_one_store_fails_its_keys_naming_it(write_pipeline, small_release, tmp_path):
    # A sweep's later cell reads the frames an earlier cell let go: a frame swapped meanwhile
    # for a link to another image is not sent under the old hash; its keys fail, naming it.
    import os
    import shutil

    from PIL import Image

    from povagent.exchange.images import ImageStore

    release = tmp_path / "release"
    shutil.copytree(small_release, release)
    images = ImageStore()
    backend = {"name": "test-center", "options": {"encode": True}}
    first = run(write_pipeline(backend=backend, dataset={"path": str(release)}), images=images)
    assert first.summary.rows.answered == N_KEYS
    frame = sorted(release.rglob("exploration_images/*.png"))[0]
    other = release / "swapped.png"  # inside the dataset, so loading it again accepts it
    Image.new("RGB", Image.open(frame).size, (255, 0, 255)).save(other)
    frame.unlink()
    os.symlink(other, frame)
    again = run(write_pipeline("again.yaml", backend=backend, dataset={"path": str(release)}, output=str(tmp_path / "again")),
                images=images)
    failed = [r for r in rows_of(again) if r.status == "infra_error"]
    assert failed and all(frame.name in (r.error_message or "") and "changed since it was first read" in r.error_message for r in failed)
    assert {r.house_id for r in failed} == {frame.parents[1].name}


def test_request_event_per_call_in_the_log(write_pipeline):
    result = run(write_pipeline(instances={"limit": 2}))
    events = [json.loads(line) for line in (result.run_dir / "log.jsonl").read_text().splitlines()]
    requests = [e for e in events if e["event"] == "request"]
    assert len(requests) == 2
    assert {"latency_s", "prompt_tokens", "completion_tokens", "cost_usd", "retries", "cached"} <= set(requests[0])


def test_each_distinct_image_is_read_and_encoded_once_per_run(write_pipeline, small_release):
    from povagent.dataset import load_dataset
    from povagent.exchange.images import ImageStore

    distinct = {f.file for inst in load_dataset(small_release).instances() for f in inst.frames}
    images = ImageStore()
    result = run(write_pipeline(backend={"name": "test-center", "options": {"encode": True}}, runs=2), images=images)
    assert result.stats.requests == 2 * N_KEYS
    assert images.stats.file_reads == len(distinct) and images.stats.base64_encodes == len(distinct)
    assert images.stats.rebuilds == 0 and result.summary.images.distinct == len(distinct)


def test_summary_after_resume_covers_the_rows_of_both_sessions(write_pipeline):
    from povagent.run.summary import summarize_run
    from povagent.run.summary_model import RunSummary

    run(write_pipeline(instances={"limit": 5}))
    result = run(write_pipeline())
    fresh = RunSummary.model_validate(summarize_run(result.run_dir / "results.jsonl"))
    assert result.summary.rows.done == N_KEYS and result.summary.rows.missing == 0
    for part in ("overall", "per_condition", "per_direction", "per_run", "usage"):
        assert getattr(result.summary, part) == getattr(fresh, part), part


def test_a_bad_house_is_logged_by_file_and_skipped(write_pipeline, mini_root):
    result = run(write_pipeline(dataset={"path": str(mini_root)}))
    events = [json.loads(line) for line in (result.run_dir / "log.jsonl").read_text().splitlines()]
    problems = [e for e in events if e["event"] == "dataset_problem"]
    assert problems and all(e["file"].startswith("artifacts/train_house_00002/") for e in problems)
    assert all(e["level"] == "warning" and e["path"] and e["problem"] for e in problems)
    assert {r.house_id for r in rows_of(result)} == {"train_house_00000", "train_house_00001"}


def test_strict_dataset_stops_before_any_request(write_pipeline, mini_root, offline_plugin, tmp_path):
    from povagent.errors import DatasetError

    with pytest.raises(DatasetError, match=r"train_house_00002"):
        run(write_pipeline(dataset={"path": str(mini_root), "strict": True}))
    assert offline_plugin.CALLS["count"] == 0 and not (tmp_path / "run").exists()


def test_rejected_backend_options_write_nothing_to_the_run_folder(write_pipeline, tmp_path):
    from povagent.errors import PluginError

    with pytest.raises(PluginError, match=r"rejected its options"):
        run(write_pipeline(backend={"name": "test-center", "options": {"no_such_option": 1}}))
    assert not (tmp_path / "run").exists()


def test_secret_options_are_redacted_in_the_run_folder_config(write_pipeline, povagent_host, offline_plugin, monkeypatch):
    monkeypatch.setenv("DEMO_API_KEY", "plain-secret-value-42")

    class Keyed(offline_plugin.CenterBackend):
        def __init__(self, auth_token=None, endpoint=None, api_key_env=None, **kw):
            super().__init__(**kw)

    class Plugin:
        @hookimpl
        def register_backends(self, register):
            register("keyed", Keyed)

    povagent_host.add_plugin(Plugin(), name="keyed")
    try:
        options = {"auth_token": "tok-0123456789", "endpoint": "https://x/?k=plain-secret-value-42", "api_key_env": "DEMO_API_KEY"}
        result = run(write_pipeline(backend={"name": "keyed", "options": options}, instances={"limit": 1}))
    finally:
        povagent_host.remove_plugin("keyed")
    import yaml

    saved = yaml.safe_load((result.run_dir / "config.yaml").read_text())["backend"]["options"]
    assert saved == {"auth_token": "[REDACTED]", "endpoint": "https://x/?k=[REDACTED]", "api_key_env": "DEMO_API_KEY"}


def test_image_files_are_read_off_the_event_loop(write_pipeline, monkeypatch):
    import threading

    from povagent.exchange.images import ImageStore

    readers = []
    original = ImageStore._read_file

    def spy(self, path):
        readers.append(threading.current_thread() is threading.main_thread())
        return original(self, path)

    monkeypatch.setattr(ImageStore, "_read_file", spy)
    run(write_pipeline(runs=2))
    assert readers and not any(readers)


def test_an_unreadable_frame_is_found_at_load_naming_the_file_and_the_run_goes_on(write_pipeline, small_release, tmp_path):
    # Images are checked when the dataset loads (issue 14): the house is reported and skipped
    # before any request, instead of turning into failed rows mid-run.
    import shutil

    release = tmp_path / "release"
    shutil.copytree(small_release, release)
    frame = sorted(release.glob("artifacts/*/exploration_images/*.png"))[0]
    # a folder in the frame's place: listed as a frame, unreadable as one (a deleted frame is
    # simply not shown: the official frame list is the folder's PNGs)
    frame.unlink()
    frame.mkdir()
    result = run(write_pipeline(dataset={"path": str(release)}, instances={"conditions": ["a"]}))
    rows = rows_of(result)
    assert rows and not [r for r in rows if r.house_id == frame.parts[-3]]
    assert all(r.status == "answered" for r in rows)
    events = [json.loads(line) for line in (result.run_dir / "log.jsonl").read_text().splitlines()]
    assert [e for e in events if e["event"] == "dataset_problem" and frame.name in e["problem"]]


def test_a_results_file_that_cannot_be_written_stops_the_run_with_a_clear_error(write_pipeline, monkeypatch, caplog):
    import errno
    import gc

    from povagent.errors import ResultsError
    from povagent.results.rows import ResultsWriter

    written = []
    original = ResultsWriter.write_lines

    def fill_up(self, text):
        if written:
            raise OSError(errno.ENOSPC, "No space left on device")
        written.append(text)
        original(self, text)

    monkeypatch.setattr(ResultsWriter, "write_lines", fill_up)
    path = write_pipeline(backend={"name": "test-center", "options": {"delay_s": 0.01}}, concurrency=1)
    with pytest.raises(ResultsError, match=r"results.jsonl: cannot write \(No space left on device\); the rows already written are kept.*resume"):
        run(path)
    kept = (path.parent / "run" / "results.jsonl").read_text().splitlines()
    assert len(kept) == len(written[0].splitlines()) >= 1
    summary = json.loads((path.parent / "run" / "summary.json").read_text())
    assert summary["interrupted"] is True and summary["rows"]["done"] == len(kept)
    gc.collect()
    assert not [r for r in caplog.records if "never retrieved" in r.getMessage()]


def test_a_second_process_on_the_same_run_folder_is_refused(write_pipeline, tmp_path, offline_plugin):
    import fcntl

    run_dir = tmp_path / "run"
    run_dir.mkdir()
    with open(run_dir / ".lock", "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)  # as a running `povagent run` holds it
        with pytest.raises(ConfigError, match=r"another povagent process is running a pipeline into this folder"):
            run(write_pipeline())
    assert offline_plugin.CALLS["count"] == 0 and not (run_dir / "results.jsonl").exists()
    assert run(write_pipeline()).summary.complete  # released: the folder is usable again


def test_answers_are_cached_off_the_event_loop_before_their_rows_are_durable(write_pipeline, monkeypatch, tmp_path):
    import threading

    from povagent.engine.cache import ResponseCache, cache_key, identity_json
    from povagent.results.rows import ResultsWriter

    stored: set[str] = set()
    on_loop = []
    insert, write_lines = ResponseCache._insert, ResultsWriter.write_lines

    def spy_insert(self, records):
        on_loop.append(threading.current_thread() is threading.main_thread())
        insert(self, records)
        stored.update(r[0] for r in records)

    identity = identity_json({"backend": "test-center", "reply": None})
    uncached_rows = []

    def spy_write(self, text):
        for line in text.splitlines():
            row = json.loads(line)
            if cache_key(identity, row["exchanges"][0]["request_hash"], row["run"]) not in stored:
                uncached_rows.append(row["key"])
        write_lines(self, text)

    monkeypatch.setattr(ResponseCache, "_insert", spy_insert)
    monkeypatch.setattr(ResultsWriter, "write_lines", spy_write)
    cache = str(tmp_path / "c.sqlite")
    result = run(write_pipeline(cache=cache, runs=2, backend={"name": "test-center", "options": {"delay_s": 0.005}}))
    assert result.stats.requests == 2 * N_KEYS and len(stored) == 2 * N_KEYS
    assert on_loop and not any(on_loop) and uncached_rows == []


def test_a_cache_that_cannot_be_written_costs_calls_not_the_run(write_pipeline, offline_plugin, monkeypatch, tmp_path):
    import sqlite3

    from povagent.engine.cache import ResponseCache

    def broken(self, records):
        raise sqlite3.OperationalError("disk I/O error")

    cache = str(tmp_path / "c.sqlite")
    with monkeypatch.context() as m:
        m.setattr(ResponseCache, "_insert", broken)
        result = run(write_pipeline(cache=cache))
    assert result.summary.complete and result.summary.rows.answered == N_KEYS
    events = [json.loads(line) for line in (result.run_dir / "log.jsonl").read_text().splitlines()]
    failed = [e for e in events if e["event"] == "cache_write_failed"]
    assert failed and all(e["level"] == "warning" and "disk I/O error" in e["error"] for e in failed)
    assert sum(e["answers_not_cached"] for e in failed) == N_KEYS
    again = run(write_pipeline(cache=cache, output=str(tmp_path / "again")))
    assert again.stats.cache_hits == 0 and offline_plugin.CALLS["count"] == 2 * N_KEYS


@pytest.mark.parametrize(("frame", "scored"), [(1, True), (2, False)])
def test_a_frame_the_strategy_did_not_show_is_no_frame(write_pipeline, frame, scored):
    # basic shows only the first 2 of the house's 3 frames: an answer naming the third names a
    # frame the model never saw, which the official runner cannot map back to an image
    reply = json.dumps({"selected_image": frame, "x": 100, "y": 100})
    path = write_pipeline(
        strategy={"name": "basic", "options": {"max_frames": 2}},
        backend={"name": "test-center", "options": {"reply": reply}},
        instances={"conditions": ["a"], "limit": 1},
    )
    (row,) = rows_of(run(path))
    assert row.status == "answered" and row.parse.selected_image == frame
    assert (row.prediction.image_path is not None) is scored
    assert row.scores["official"]["answered"] is scored
