"""Running a pipeline: every (instance, run) once, concurrently, durably, resumably.

For each pending key the strategy builds the request(s), which reach the backend through the
one request path (:class:`~povagent.engine.request_path.RequestPath`: response cache, concurrency
limit, timeout, retries on transient failures only); the parser reads the answer and the scorers
score it. Every key ends as exactly one row in ``results.jsonl``: ``answered`` (scored),
``parse_error`` (the model answered, nothing could be read) or ``infra_error`` (no answer:
retries exhausted, a permanent API error, or a plugin failure); errors are never scored.

Rows become durable through the :class:`~povagent.run.journal.RowJournal` as keys finish, so a
run killed at any moment resumes by running only the keys missing from the file; keys whose row
is ``infra_error`` are attempted again by default (:func:`~povagent.run.pending.plan_keys`).

A backend that answers in this process (:attr:`~povagent.interfaces.Backend.answers_in_process`:
the offline baselines) has its keys answered a chunk at a time, in order, on the event loop
(:meth:`~povagent.run.solve_key.KeySolver.solve_chunk`): no task, concurrency slot, timeout or
thread hand-off per key, and the same rows, events and guarantees.

Failing fast: the first pending key runs alone; when it fails in a way no other key can get
past (no API key, authentication, unknown model, an unreachable server) the run stops there
instead of failing every key. During the run, ``stop_after_failures`` consecutive
``infra_error`` rows trip a circuit breaker and stop it too. A stopped run's remaining keys
stay pending: fix the cause and run the same command again.

The run folder holds ``config.yaml`` (resolved), ``results.jsonl``, ``log.jsonl``,
``summary.json`` and the marker that makes it ours (:mod:`povagent.run.run_folder`: a folder
holding anything else is refused). What a run returns (its exit code, summary and counters) is
:mod:`povagent.run.run_result`. It must not parse YAML or print tables (:mod:`povagent.config`,
:mod:`povagent.cli.pipeline_commands`).
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
from itertools import islice
from pathlib import Path
from typing import Any

from povagent.answers.types import answer_type_misfit
from povagent.config.models import PipelineConfig
from povagent.config.pipeline import dump_pipeline
from povagent.config.remote_code import remote_code_granted
from povagent.dataset.instances import Instance
from povagent.dataset.set_interface import EvaluationSet
from povagent.engine.cache import ResponseCache
from povagent.engine.concurrency import AdaptiveConcurrency
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import error_type_of
from povagent.errors import ConfigError, ResultsError
from povagent.exchange.images import ImageStore
from povagent.exchange.transport import open_image_transport
from povagent.exchange.usage_totals import RunningTotals
from povagent.files.confined_write import write_inside
from povagent.files.folder_lock import folder_lock
from povagent.files.logs import RunLog
from povagent.files.redaction import Redactor, secrets_named_by
from povagent.plugins import PluginHost, get_plugin_host
from povagent.results.rows import STATUS_TEXT, ResultRow, RowStatus, model_label
from povagent.results.upgrade import FIELD, SUMMARY_FORMAT
from povagent.run.components import ComponentNames, answering_model, backend_label, create_components, pipeline_hash
from povagent.run.frozen_heap import frozen_heap, spaced_collections
from povagent.run.house_frames import FrameReader, HouseFrames
from povagent.run.journal import RowJournal, drop_rows
from povagent.run.pending import RESULTS, asked_by, plan_keys, prepare_dataset, select_instances
from povagent.run.progress import QuietProgress, RunProgress
from povagent.run.run_folder import claim_folder
from povagent.run.run_result import RunResult, RunStats
from povagent.run.solve_key import KeySolver
from povagent.run.stop_signals import cancelled_on_stop, finish_through_stop, stop_requested
from povagent.run.summary import declared_metrics, summarize_run, write_summary, written_rows_table
from povagent.run.summary_model import RunSummary
from povagent.scoring.metrics import Declared
from povagent.scoring.score_protocols import scorer_protocols

LOG = "log.jsonl"
SUMMARY = "summary.json"
CONFIG = "config.yaml"

#: Failure kinds of the first key that stop a run before it fans out: no other key can get
#: past them until the user changes something.
FAIL_FAST_KINDS = frozenset({"auth", "missing_key", "not_found", "connection", "client_import", "load_failed"})
#: Fail-fast kinds found before anything was sent (an unset key variable, a model client that
#: cannot be imported): the command says so in one line, so the run logs them to its file only,
#: not as console warnings above that line.
SET_UP_KINDS = frozenset({"missing_key", "client_import"})
#: Keys a backend answering in this process answers between two turns of the event loop (the
#: journal's committer, a stop signal), and the time after which a chunk ends sooner (a slow
#: baseline): rows still become durable, and a stop is still heard, as keys finish.
CHUNK, CHUNK_S = 64, 0.05


# -- the run -------------------------------------------------------------------------------------
class _LimitEvents:
    """Where the adaptive limiter reports a change: the run's log and the progress bar."""

    def __init__(self, log: RunLog, progress: RunProgress) -> None:
        self._log, self._progress = log, progress

    def info(self, event: str, **fields: Any) -> None:
        self._log.info(event, **fields)
        if "limit" in fields and "maximum" in fields:
            self._progress.concurrency(int(fields["limit"]), int(fields["maximum"]))


class StopRun(Exception):
    """Raised inside the run to stop fanning out (fail fast, circuit breaker)."""


class PipelineRun:
    """One pipeline run into its folder. Use :func:`run_pipeline` unless embedding."""

    def __init__(
        self,
        config: PipelineConfig,
        *,
        host: PluginHost | None = None,
        dataset: EvaluationSet | None = None,
        images: ImageStore | None = None,
        cache: ResponseCache | None = None,
        progress: RunProgress | None = None,
        console_log: bool = False,
        retry_failed: bool = True,
        trust_remote_code: bool = False,
    ) -> None:
        self.config = config
        #: the caller's grant of a checkpoint's own code (never the config's: see
        #: :mod:`povagent.config.remote_code`)
        self.trust_remote_code = trust_remote_code
        self.host = host or get_plugin_host(config.plugins)
        self.dataset = dataset
        self.images = images or ImageStore(max_bytes=config.images.max_mb * 1024 * 1024)
        self._cache = cache
        self._own_cache = cache is None
        self.progress = progress or QuietProgress()
        self.console_log = console_log
        self.retry_failed = retry_failed
        self.run_dir = Path(config.output)
        self.stats = RunStats()
        self.config_hash = config.config_hash()
        # every key the config names (api_key_env) is removed from messages, logs and echoed answers
        self._redactor = Redactor(secrets_named_by(config.resolved_dict()))
        self._declared: Declared = {}  # each scorer's declared metrics, set with the components
        #: what the rows written in this session spent (``session`` in summary.json), summed as they come
        self._session_spent = RunningTotals()
        self._frames = FrameReader(self.images)
        self._failures_in_a_row = 0
        self._stopped: str | None = None
        self._stop_kind: str | None = None

    # -- one key -------------------------------------------------------------------------------
    def _log_retry(self, row_id: str, exc: BaseException, failed_attempts: int, wait_s: float) -> None:
        self._log.info(
            "retry",
            row=row_id,
            attempt=failed_attempts,
            error_type=error_type_of(exc),
            error=self._redactor.text(f"{type(exc).__name__}: {exc}"),
            wait_s=round(wait_s, 3),
        )

    def _log_bug(self, row_id: str, message: str, trace: str) -> None:
        self._log.error("backend_exception", row=row_id, error=message, traceback=trace)

    def _before_rows(self) -> None:
        """Runs in the journal's thread before each batch of rows is written."""
        self._log.flush()
        self._flush_cache()

    def _flush_cache(self) -> None:
        """Store the answers queued in the response cache. The cache only saves calls: when it
        cannot be written, the answers are dropped from it with a warning and the run goes on."""
        cache = self._cache
        if cache is None or not cache.pending:
            return
        try:
            cache.flush()
        except Exception as exc:
            dropped = cache.discard_pending()
            self._log.warning("cache_write_failed", path=str(cache.path), answers_not_cached=dropped,
                              error=self._redactor.text(f"{type(exc).__name__}: {exc}"))

    def _reported(self, row: ResultRow) -> None:
        """A row is durable: count it, show it, tell the observers."""
        s = self.stats
        s.rows_written += 1
        status = STATUS_TEXT.get(row.status) or row.status.value  # (an enum's value is a descriptor call)
        s.statuses[status] += 1
        self._session_spent.add(row)  # UsageTotals.of((spent, row), unstated 0), in place
        if row.status is RowStatus.INFRA_ERROR:
            log = self._log.info if row.error_type in SET_UP_KINDS else self._log.warning
            log("infra_error", row=row.key, error_type=row.error_type, error=row.error_message)
        self.progress.advance(status)
        if self._written is not None:
            self._written.add(row)
        if self._observed:
            self.host.hooks.instance_done(str(self.run_dir), row)

    def _report_dataset_problems(self) -> None:
        """Say which houses or pairs loading skipped (file, JSON path, sentence): never silently."""
        problems = self.dataset.problems  # type: ignore[union-attr]  # called after the dataset is loaded
        for p in problems:
            self._log.warning("dataset_problem", file=p.file, path=p.json_path, problem=p.message)
        if problems:
            self._log.warning(
                "dataset_problems",
                count=len(problems),
                hint="the houses or pairs named above were skipped; `povagent validate` lists every problem, --strict stops instead",
            )

    def _after_row(self, row: ResultRow, first: bool) -> None:
        """Fail fast on the first key and keep the circuit breaker's count (raises StopRun)."""
        if row.status is not RowStatus.INFRA_ERROR:
            self._failures_in_a_row = 0
            return
        self._failures_in_a_row += 1
        where = self._redactor.text(backend_label(self.components.backend))  # URL credentials never shown
        if first and row.error_type in FAIL_FAST_KINDS:
            self._stop_kind = row.error_type
            self._stopped = (
                f"the first request failed ({row.error_type}: {row.error_message}); {where}: nothing else was sent. "
                "Fix the key, the model name or the server, then run the same command again to resume"
            )
            raise StopRun(self._stopped)
        limit = self.config.stop_after_failures
        if limit and self._failures_in_a_row >= limit:
            self._stopped = (
                f"{self._failures_in_a_row} keys in a row failed (last: {row.error_type}: {row.error_message}); "
                f"{where}: stopped instead of retrying every key. Fix the cause, then run the same command again to resume"
            )
            raise StopRun(self._stopped)

    # -- the whole run -------------------------------------------------------------------------
    async def run(self) -> RunResult:
        """Run every pending key; write the run folder; return the summary."""
        with spaced_collections():  # the set's reading and the keys make almost no cyclic garbage
            return await self._run()

    async def _run(self) -> RunResult:
        t_start = time.perf_counter()
        config = self.config
        # Plugins check their options first: a rejected option (a literal API key, say) fails
        # before the dataset is read and before anything is written to the run folder.
        with remote_code_granted(self.trust_remote_code):
            self.components = create_components(config, self.host)
        self._declared = declared_metrics(self.components.scorers)  # what the summary breaks down
        self._protocols: dict[str, str] = dict(scorer_protocols(self.components.scorers))  # which follows which protocol
        self.config_hash = pipeline_hash(config, self.components.strategy)
        # the backend's own options too: a profile may name the key's variable (api_key_env)
        options: Any = getattr(self.components.backend, "options", None)
        dumped = options.model_dump() if hasattr(options, "model_dump") else options
        self._redactor = Redactor(secrets_named_by(config.resolved_dict()) + secrets_named_by(dumped))
        self.components.backend.check_image_transport(config.images.transport)
        if self._will_send():
            # a client library (litellm: seconds) loads in the background meanwhile
            self.components.backend.preload()
        # a set handed in (sweeps share one loaded set) is asked the pipeline's task too
        self.dataset = prepare_dataset(config) if self.dataset is None else asked_by(config, self.dataset)
        instances = select_instances(self.dataset, config)
        if not instances:
            raise ConfigError(f"no instances selected from {config.dataset.root} (check instances: conditions, directions, houses)")
        self.dataset.check_scorers(self.components.scorers)  # a real-world set has no 3D GT
        if self.components.answer_type is not None and (misfit := answer_type_misfit(config.strategy.name, self.components.answer_type, instances)):
            raise ConfigError(misfit)  # a strategy asking a type the instances do not ask for: before any request
        # ours to write, or refused before anything is written (someone's folder, read-only)
        claim_folder(self.run_dir, "run")
        self.components.strategy.use_run_folder(self.run_dir)
        with folder_lock(self.run_dir), open_image_transport(
            config.images, self.images, dataset_root=self.dataset.root, output=self.run_dir
        ), cancelled_on_stop(), frozen_heap():  # the loaded set is not walked by each full collection of the run
            return await self._run_in_folder(instances, t_start)

    def _will_send(self) -> bool:
        """Whether this run will surely send a request, known before the dataset is read: the
        run folder has no row yet and no response cache can answer (none, or an empty one).
        Otherwise the backend starts only when a request misses the cache, so a run whose
        every answer is cached never loads the client library."""
        results = self.run_dir / RESULTS
        if results.exists() and results.stat().st_size:
            return False
        if not getattr(self.components.backend, "cacheable", True):
            return True
        if self._cache is not None:
            return False  # a cache handed in (a sweep's shared one) may hold every answer
        path = self.config.cache_path()
        return path is None or not path.exists() or path.stat().st_size == 0

    async def _run_in_folder(self, instances: list[Instance], t_start: float) -> RunResult:
        """The run proper, with the run folder locked against a second process."""
        config = self.config
        plan = plan_keys(config, instances, config_hash=self.config_hash, retry_failed=self.retry_failed)
        retried = plan.failed if self.retry_failed else set()
        if retried:
            # the failed rows go before their keys run again, so a retried key has one row
            drop_rows(self.run_dir / RESULTS, retried)
        pending, wanted, n_pending = plan.pending, plan.wanted, len(plan.pending)
        self._wanted = wanted  # the summary's keys: made once
        del plan  # its done keys: the summary reads the rows (as written, or back) instead
        self._written = written_rows_table(self.run_dir / RESULTS, wanted, self._declared, self._protocols)
        write_inside(self.run_dir, CONFIG, dump_pipeline(config, self._redactor))

        backend = self.components.backend
        assert config.backend is not None and config.parser is not None, "resolve_components() first"
        self._names = ComponentNames(config.backend.name, config.strategy.name, config.parser.name)
        self._model = answering_model(backend)
        self._observed = bool(self.host.hooks.active)
        cache_path = config.cache_path()
        if self._cache is None and cache_path is not None and getattr(backend, "cacheable", True):
            self._cache = ResponseCache(cache_path)
        self._log = RunLog(self.run_dir / LOG, console=self.console_log, redactor=self._redactor, run=str(self.run_dir))
        self._path = RequestPath(
            backend,
            self.images,
            policy=config.retry,
            timeout_s=config.timeout,
            cache=self._cache,
            limiter=AdaptiveConcurrency(config.concurrency, log=_LimitEvents(self._log, self.progress)),
            redact=self._redactor.text,
            redact_answer=self._redactor.known,
            on_retry=self._log_retry,
            on_bug=self._log_bug,
            start_backend=True,
        )
        # Before each batch of rows is written (in the journal's thread, off the event loop) the
        # log is pushed to the OS and queued answers are stored in the cache: after a kill, every
        # durable row has its request events in log.jsonl and its answers in the cache.
        self._journal = RowJournal(self.run_dir / RESULTS, self._reported, before_write=self._before_rows)
        self._report_dataset_problems()

        self._log.info("run_start", n_total=len(wanted), n_pending=len(pending), config_hash=self.config_hash,
                       backend=self._names.backend, model=model_label(*self._model), strategy=self._names.strategy, parser=self._names.parser,
                       retried_failed_keys=len(retried))
        self.host.hooks.run_start(str(self.run_dir), config.resolved_dict(), len(pending), len(wanted))
        self.progress.start(len(wanted), len(wanted) - len(pending))
        interrupted, failing = True, False
        try:
            # The backend starts (litellm: an import of seconds) when the first request misses
            # the response cache, before that request's clock starts (RequestPath).
            await self._fan_out(pending)
            interrupted = False
        except StopRun:
            interrupted = False
        except BaseException:
            failing = True  # the first failure is the one reported, not the summary's after it
            raise
        finally:
            # A stop (SIGTERM, Ctrl-C) that arrives from here on is held until the run folder is
            # complete: the journal closed, summary.json written, then it goes on (see below).
            self.progress.stop()
            self.stats.wall_s = time.perf_counter() - t_start
            pending.clear()  # the keys' tuples go before the summary reads the rows back
            stop_came = await finish_through_stop(self._journal.aclose())
            self._flush_cache()  # answers of keys that did not finish (an interrupted run)
            self.stats.fsyncs, self.stats.fsync_s = self._journal.fsyncs, self._journal.fsync_s
            self.stats.requests, self.stats.cache_hits, self.stats.retries = (
                self._path.stats.requests,
                self._path.stats.cache_hits,
                self._path.stats.retries,
            )
            if self._stopped:
                stop_log = self._log.info if self._stop_kind in SET_UP_KINDS else self._log.error
                stop_log("run_stopped", reason=self._stopped)
            written = {FIELD: SUMMARY_FORMAT, **self.summarize(interrupted or stop_came)}  # what the file holds, for run_end too
            # a stop requested while the summary was computed (plain code: not yet delivered) too
            written["interrupted"] = written["interrupted"] or stop_requested()
            try:
                summary = write_summary(self.run_dir / SUMMARY, written)
            except OSError as exc:  # a full disk: reported below, once the run is closed
                unwritten: OSError | None = exc
                summary = RunSummary.model_validate(written)
            else:
                unwritten = None
            self._log.info("run_end", interrupted=summary.interrupted, stopped=self._stopped,
                           **{k: v for k, v in self.stats.as_dict().items() if k != "statuses"})
            self.host.hooks.run_end(str(self.run_dir), written)
            self._log.close()
            try:
                stop_came = await finish_through_stop(backend.aclose()) or stop_came
            finally:
                if self._own_cache and self._cache is not None:
                    self._cache.close()
            if unwritten is not None and not failing:
                raise ResultsError.cannot_write(self.run_dir / SUMMARY, unwritten) from unwritten
            if stop_came and not interrupted:
                # every key had finished when the stop came: the folder is complete, and the
                # stop still ends the command (a sweep must not start its next cell)
                raise asyncio.CancelledError
        return RunResult(self.run_dir, summary, self.stats, len(wanted), n_pending, interrupted, self._stopped, self._stop_kind)

    async def _fan_out(self, pending: list[tuple[Instance, int]]) -> None:
        """Run ``pending``: the first key alone (fail fast), then the rest with ``concurrency``
        workers pulling keys in order (bounded memory; a house's frames stay hot), or, for a
        backend answering in this process, a chunk of keys at a time in order."""
        if not pending:
            return
        solver = KeySolver(
            self.components,
            self._names,
            self._model,
            self.config_hash,
            self._path,
            self.images,
            self.dataset,
            self._log,
            self._redactor,
            self._frames.read,
            label=self.config.label,
        )
        solve = solver.solve
        with HouseFrames(self.images, pending) as houses:
            first, rest = pending[0], islice(pending, 1, None)  # no copy of the list
            row = await solve(*first)
            houses.done(first[0])
            self._journal.submit(row)
            await self._journal.drain()
            self._after_row(row, first=True)

            def finished(instance: Instance, row: ResultRow) -> None:
                houses.done(instance)
                self._journal.submit(row)
                self._after_row(row, first=False)

            async def worker() -> None:
                for instance, run in rest:
                    finished(instance, await solve(instance, run))
                    # Let the committer run even when the backend answers without suspending
                    # (offline baselines): rows become durable as they finish, not at the end.
                    await self._journal.backpressure()

            async def in_chunks() -> None:
                # A backend answering in this process: keys a chunk at a time, in order, with no
                # task, slot, timeout or thread hand-off each (see Backend.answers_in_process).
                while chunk := await solver.solve_chunk(rest, CHUNK, CHUNK_S):
                    for instance, row in chunk:
                        finished(instance, row)
                    await self._journal.backpressure()  # the committer writes this chunk meanwhile

            try:
                if getattr(self.components.backend, "answers_in_process", False):
                    await in_chunks()
                else:
                    async with asyncio.TaskGroup() as group:
                        for _ in range(min(self.config.concurrency, len(pending) - 1)):
                            group.create_task(worker())
                await self._journal.drain()
            except BaseException as exc:
                failed = self._journal.error
                if failed is not None:  # a full disk, a lost mount: the user's to fix, not a bug
                    # the file that failed: results.jsonl, or log.jsonl flushed before each batch
                    path = getattr(failed, "filename", None) or self.run_dir / RESULTS
                    raise ResultsError.cannot_write(path, failed) from failed
                if isinstance(exc, StopRun):
                    await self._journal.drain()  # rows finished before the stop are kept
                    raise
                if isinstance(exc, BaseExceptionGroup):
                    stop = exc.subgroup(StopRun)
                    if stop is not None and stop.exceptions:
                        await self._journal.drain()  # rows finished before the stop are kept
                        raise StopRun(self._stopped) from None
                    if len(exc.exceptions) == 1:
                        raise exc.exceptions[0] from None  # one worker's bug: its own traceback, not a group's
                raise

    def summarize(self, interrupted: bool) -> dict[str, Any]:
        """What ``summary.json`` holds (the JSON of a :class:`RunSummary`): the official breakdown over the
        selected keys (rows as written if the file started empty and no write failed, else read back), plus the run's counters."""
        summary = summarize_run(self.run_dir / RESULTS, self._wanted, self._declared, self._protocols, None if self._journal.error else self._written)
        spent = self._session_spent.totals()
        self.stats.prompt_tokens, self.stats.completion_tokens = spent.prompt_tokens or 0, spent.completion_tokens or 0
        self.stats.cost_usd = spent.cost_usd or 0.0
        summary["pipeline"] = {
            "backend": self._names.backend,
            "model": self._model[0],
            "profile": self._model[1],
            "strategy": self._names.strategy,
            "parser": self._names.parser,
            "scorers": list(self.components.scorers),
            "config_hash": self.config_hash,
        }
        summary["complete"] = summary["rows"]["missing"] == 0
        summary["interrupted"] = interrupted
        summary["stopped"] = self._stopped
        summary["session"] = self.stats.as_dict()
        summary["images"] = {**dataclasses.asdict(self.images.stats), "distinct": self.images.distinct}
        return summary


async def run_pipeline_async(config: PipelineConfig, **kwargs: Any) -> RunResult:
    """Run a pipeline inside an existing event loop (see :class:`PipelineRun` for options)."""
    return await PipelineRun(config, **kwargs).run()


def run_pipeline(config: PipelineConfig, **kwargs: Any) -> RunResult:
    """Run a pipeline to completion (resuming from its folder); see :class:`PipelineRun`."""
    return asyncio.run(run_pipeline_async(config, **kwargs))
