"""Running a pipeline: every (instance, run) once, concurrently, durably, resumably.

For each pending key the strategy builds the request(s), the backend answers through the
response cache, with tenacity retries on transient failures only and a per-request timeout,
the parser reads the answer, and the scorers score it. Every key ends as exactly one row in
``results.jsonl``: ``answered`` (scored), ``parse_error`` (the model answered, nothing could be
read) or ``infra_error`` (no answer: retries exhausted, a permanent API error, or a plugin
failure); errors are never scored as answers.

Rows are appended and fsynced as keys finish (rows finishing in the same event-loop tick share
one fsync, and none is reported done before it is durable), so a run killed at any moment
resumes by running only the keys missing from the file.

The run folder holds ``config.yaml`` (resolved), ``results.jsonl``, ``log.jsonl`` and
``summary.json``. This module must not parse YAML or print tables (see :mod:`povagent.config.pipeline`
and :mod:`povagent.cli.pipeline`).
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import os
import random
import time
import traceback
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Mapping

from tenacity import AsyncRetrying, retry_if_exception, stop_after_attempt

from povagent.answers.spec import ParsedAnswer, ParseStatus
from povagent.engine.cache import ResponseCache, cache_key, identity_json
from povagent.config.pipeline import PipelineConfig, dump_pipeline
from povagent.dataset.instances import Instance, row_key
from povagent.dataset.loader import Dataset, load_dataset
from povagent.errors import ConfigError, ResultsError
from povagent.exchange.messages import Request, Response
from povagent.exchange.images import ImageStore
from povagent.interfaces import Backend, Parser, PermanentBackendError, Scorer, Strategy, TransientBackendError
from povagent.run.logs import Redactor, RunLog
from povagent.plugins import PluginHost, get_plugin_host
from povagent.run.progress import QuietProgress, RunProgress
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, ResultsWriter, RowStatus, iter_rows, utc_now
from povagent.scoring.breakdown import ScoredRow, breakdown, summarize

RESULTS = "results.jsonl"
LOG = "log.jsonl"
SUMMARY = "summary.json"
CONFIG = "config.yaml"

#: Longest Retry-After honoured (a server asking for an hour is treated as asking for this).
MAX_RETRY_AFTER_S = 600.0

#: File-system errors that no retry will fix.
_PERMANENT_OS_ERRORS = (FileNotFoundError, PermissionError, IsADirectoryError, NotADirectoryError)


# -- retry classification ----------------------------------------------------------------------
def is_transient(exc: BaseException) -> bool:
    """Whether a failure is worth retrying: timeouts, connection errors, 429 and 5xx.

    Never a 4xx such as a bad request or an authentication error. Exceptions from libraries
    that carry an HTTP ``status_code``/``status`` are classified by it.
    """
    if isinstance(exc, TransientBackendError):
        return True
    if isinstance(exc, PermanentBackendError):
        return False
    if isinstance(exc, (TimeoutError, asyncio.TimeoutError, ConnectionError)):
        return True
    if isinstance(exc, _PERMANENT_OS_ERRORS):
        return False
    if isinstance(exc, OSError):
        return True
    status = _status_of(exc)
    if status is not None:
        return status in (408, 425, 429) or status >= 500
    return False


def _status_of(exc: BaseException) -> int | None:
    for attr in ("status", "status_code"):
        value = getattr(exc, attr, None)
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    return None


def error_type_of(exc: BaseException) -> str:
    """A short typed name for a failure, as stored in an ``infra_error`` row's ``error_type``."""
    if isinstance(exc, (TimeoutError, asyncio.TimeoutError)):
        return "timeout"
    status = _status_of(exc)
    if status == 429:
        return "rate_limited"
    if status is not None and status >= 500:
        return "server_error"
    if status in (401, 403):
        return "auth"
    if status == 400:
        return "bad_request"
    if status == 404:
        return "not_found"
    if isinstance(exc, TransientBackendError):
        return "transient"
    if isinstance(exc, PermanentBackendError):
        return "permanent"
    if isinstance(exc, ConnectionError) or (isinstance(exc, OSError) and not isinstance(exc, _PERMANENT_OS_ERRORS)):
        return "connection"
    return "backend_exception"


class InfraFailure(Exception):
    """No answer for a key: the last error after retries, typed, with the attempts made."""

    def __init__(self, error_type: str, message: str, attempts: int) -> None:
        super().__init__(message)
        self.error_type = error_type
        self.message = message
        self.attempts = attempts


# -- instances ----------------------------------------------------------------------------------
def select_instances(dataset: Dataset, config: PipelineConfig) -> list[Instance]:
    """The instances a pipeline covers, in dataset order (grouped by house).

    Filter by conditions, directions and houses; then ``sample`` N with ``seed`` (kept in
    dataset order so each house's frames are read together); then keep the first ``limit``.
    """
    f = config.instances
    if f.houses:
        unknown = sorted(set(f.houses) - set(dataset.houses))
        if unknown:
            raise ConfigError(f"instances.houses: unknown house id(s) {', '.join(unknown)} in {dataset.root}")
    chosen = dataset.instances(f.conditions, f.directions, f.houses)
    if f.sample is not None and f.sample < len(chosen):
        keep = sorted(random.Random(f.seed).sample(range(len(chosen)), f.sample))
        chosen = [chosen[i] for i in keep]
    if f.limit is not None:
        chosen = chosen[: f.limit]
    return chosen


def prepare_dataset(config: PipelineConfig) -> Dataset:
    """Load the dataset, generating it first for a ``generate:`` spec whose folder is empty."""
    spec = config.dataset
    if spec.generate is not None:
        g = spec.generate
        if not (g.out / "artifacts").is_dir():
            from povagent.generate import generate_dataset  # heavy (trimesh): only when asked

            generate_dataset(
                g.out, houses=g.houses, seed=g.seed, frames=g.frames,
                judge=g.judge.name, judge_options=g.judge.options, plugins=config.plugins,
            )  # fmt: skip
    from povagent.dataset.realworld import is_realworld, load_realworld

    if is_realworld(spec.root):
        return load_realworld(spec.root)
    return load_dataset(spec.root, strict=spec.strict)


# -- the run folder ------------------------------------------------------------------------------
LOCK = ".lock"


@contextlib.contextmanager
def folder_lock(run_dir: Path) -> Iterator[None]:
    """Hold an exclusive lock on a run folder: two processes appending to one ``results.jsonl``
    would each run the keys the other is running, and write them twice.

    An advisory ``flock`` on ``<run_dir>/.lock``; the kernel drops it when the process dies,
    even by SIGKILL, so a killed run never leaves its folder locked. Where ``fcntl`` does not
    exist (Windows) the folder is not locked.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        yield
        return
    fh = open(run_dir / LOCK, "a")
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ConfigError(
                f"{run_dir}: another povagent process is running a pipeline into this folder; "
                f"wait for it to finish (then run again to resume) or choose another output folder"
            ) from None
        yield
    finally:
        fh.close()  # closing releases the lock


# -- durable rows --------------------------------------------------------------------------------
class RowJournal(ResultsWriter):
    """``results.jsonl`` with group commit.

    :meth:`submit` queues a finished row and returns at once, so a worker moves on to its next
    key while the row is being made durable. Queued rows are written and fsynced together,
    in a worker thread (the event loop keeps serving requests meanwhile); only then is
    ``on_durable(row)`` called for each, which is where progress and observers hear of it.
    ``before_write()``, when given, runs in that thread before each batch is written (the
    runner pushes its log to the OS and stores queued answers in the response cache there); if
    it raises, the batch is not written and the run stops as for a failed write.
    """

    def __init__(
        self, path: str | Path, on_durable: Callable[[ResultRow], None], before_write: Callable[[], None] | None = None
    ) -> None:
        super().__init__(path)
        self._on_durable = on_durable
        self._before_write = before_write
        self._queue: list[tuple[str, ResultRow]] = []
        self._committer: asyncio.Task[None] | None = None
        self.error: BaseException | None = None
        self.fsyncs = 0
        self.fsync_s = 0.0

    def submit(self, row: ResultRow) -> None:
        """Queue a finished row for the next batch (raises if an earlier batch failed)."""
        if self.error is not None:
            raise self.error
        self._queue.append((row.model_dump_json() + "\n", row))
        if self._committer is None or self._committer.done():
            self._committer = asyncio.get_running_loop().create_task(self._commit_loop())

    async def _commit_loop(self) -> None:
        while self._queue and self.error is None:
            # Yield once so rows finishing in this same tick join the batch.
            await asyncio.sleep(0)
            batch, self._queue = self._queue, []
            try:
                await asyncio.to_thread(self._write, "".join(line for line, _ in batch))
            except Exception as exc:  # a full disk ends the run; the rows are not reported
                # Kept here and raised to the workers by submit()/drain(); the task itself ends
                # quietly (re-raising would leave an exception nobody retrieves).
                self.error = exc
                return
            except BaseException as exc:  # cancelled mid-write: the batch's fate is unknown
                self.error = exc
                raise
            for _, row in batch:
                self._on_durable(row)

    async def backpressure(self, max_queued: int = 256) -> None:
        """Yield to the event loop; wait for the committer while too many rows are queued."""
        await asyncio.sleep(0)
        while len(self._queue) >= max_queued and self._committer is not None and not self._committer.done():
            await asyncio.shield(self._committer)

    async def drain(self) -> None:
        """Wait until every submitted row is durable; re-raise a write failure."""
        while self._committer is not None and not self._committer.done():
            await asyncio.shield(self._committer)
        if self.error is not None:
            raise self.error

    async def aclose(self) -> None:
        """Make what was submitted durable (also after a cancellation), then close the file."""
        try:
            await self.drain()
        except BaseException:  # already reported by the run; closing must still happen
            pass
        self.close()

    def _write(self, text: str) -> None:
        if self._before_write is not None:
            self._before_write()
        t0 = time.perf_counter()
        self.write_lines(text)
        self.fsyncs += 1
        self.fsync_s += time.perf_counter() - t0


# -- the run -------------------------------------------------------------------------------------
@dataclass
class RunStats:
    """What this session did (a resumed run counts only its own calls)."""

    requests: int = 0
    cache_hits: int = 0
    retries: int = 0
    rows_written: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    cost_usd: float = 0.0
    wall_s: float = 0.0
    fsyncs: int = 0
    fsync_s: float = 0.0
    statuses: Counter = field(default_factory=Counter)

    def as_dict(self) -> dict[str, Any]:
        """JSON-able form."""
        d = dataclasses.asdict(self)
        d["statuses"] = dict(self.statuses)
        return d


@dataclass
class RunResult:
    """What :func:`run_pipeline` returns."""

    run_dir: Path
    summary: dict[str, Any]
    stats: RunStats
    n_total: int
    n_pending: int
    interrupted: bool = False


@dataclass
class Components:
    """The plugins a run uses, created once."""

    backend: Backend
    strategy: Strategy
    parser: Parser
    scorers: dict[str, Scorer]


def create_components(config: PipelineConfig, host: PluginHost) -> Components:
    """Instantiate the backend, strategy, parser and scorers named in ``config``."""
    assert config.backend is not None and config.parser is not None, "resolve_components() first"
    return Components(
        backend=host.create("backend", config.backend.name, config.backend.options),
        strategy=host.create("strategy", config.strategy.name, config.strategy.options),
        parser=host.create("parser", config.parser.name, config.parser.options),
        scorers={s.name: host.create("scorer", s.name, s.options) for s in config.scorers},
    )


class PipelineRun:
    """One pipeline run into its folder. Use :func:`run_pipeline` unless embedding."""

    def __init__(
        self,
        config: PipelineConfig,
        *,
        host: PluginHost | None = None,
        dataset: Dataset | None = None,
        images: ImageStore | None = None,
        cache: ResponseCache | None = None,
        progress: RunProgress | None = None,
        console_log: bool = False,
        retry_errors: bool = False,
    ) -> None:
        self.config = config
        self.host = host or get_plugin_host(config.plugins)
        self.dataset = dataset
        self.images = images or ImageStore(max_bytes=config.images.max_mb * 1024 * 1024)
        self._cache = cache
        self._own_cache = cache is None
        self.progress = progress or QuietProgress()
        self.console_log = console_log
        self.retry_errors = retry_errors
        self.run_dir = Path(config.output)
        self.stats = RunStats()
        self.config_hash = config.config_hash()
        self._redactor = Redactor()
        self._digests: dict[str, RowDigest] = {}
        self._reads: dict[Path, asyncio.Future[Any]] = {}
        self._frames_read: dict[int, tuple[Any, ...]] = {}
        self._frames_waits: dict[int, tuple[tuple[Any, ...], set[asyncio.Future[Any]]]] = {}

    # -- setup ---------------------------------------------------------------------------------
    def _check_folder(self, keys: set[str]) -> set[str]:
        """Keys already done in the run folder; refuse a folder made by another pipeline."""
        results = self.run_dir / RESULTS
        done: set[str] = set()
        errored: set[str] = set()
        for row in iter_rows(results):
            if row.config_hash and row.config_hash != self.config_hash:
                raise ConfigError(
                    f"{self.run_dir}: holds rows of a different pipeline (config hash {row.config_hash}, this one "
                    f"{self.config_hash}: backend, strategy, parser or scorers differ); choose another output folder"
                )
            done.add(row.key)
            if row.key in keys:
                # Read once here; the summary is kept from these and never re-parses the file.
                self._digests[row.key] = digest(row)
            if row.status is RowStatus.INFRA_ERROR:
                errored.add(row.key)
        if self.retry_errors and errored:
            self._drop_rows(results, errored)
            done -= errored
            for key in errored:
                self._digests.pop(key, None)
        return done

    def _drop_rows(self, results: Path, keys: set[str]) -> None:
        # Rewrite without the failed rows (atomically) so the retried rows are not duplicates.
        tmp = results.with_suffix(".jsonl.tmp")
        with open(results, encoding="utf-8") as src, open(tmp, "w", encoding="utf-8") as dst:
            for line in src:
                if not line.endswith("\n"):
                    continue
                key_start = line.find('"key":"')
                key = line[key_start + 7 : line.find('"', key_start + 7)] if key_start >= 0 else None
                if key not in keys:
                    dst.write(line)
            dst.flush()
            os.fsync(dst.fileno())
        os.replace(tmp, results)

    # -- one key -------------------------------------------------------------------------------
    def _make_ask(self, run: int, exchanges: list[ExchangeRecord], row_id: str) -> Callable[[Request], Any]:
        backend = self.components.backend
        cache = self._cache if getattr(backend, "cacheable", True) else None
        identity = self._identity

        async def ask(request: Request) -> Response:
            if request.run != run:
                # Offline baselines seed by run index; the cache key adds the run separately.
                request = dataclasses.replace(request, run=run)
            request_hash = request.content_hash()
            key = cache_key(identity, request_hash, run) if cache is not None else None
            response = cache.get(key) if key is not None else None  # type: ignore[union-attr]
            if response is not None:
                self.stats.cache_hits += 1
            else:
                response = await self._call_backend(request, row_id)
                if key is not None:
                    # Queued, not written here: the journal's thread stores queued answers before
                    # each batch of rows, so the row holding this answer is durable only after it.
                    cache.put_deferred(key, response)  # type: ignore[union-attr]
            usage = response.usage
            # model_construct: every field is built here with the right type; validating
            # again per request cost ~0.1 ms an instance.
            exchanges.append(
                ExchangeRecord.model_construct(
                    request_hash=request_hash,
                    image_hashes=request.image_hashes(),
                    raw=response.text,
                    latency_s=response.latency_s,
                    prompt_tokens=usage.prompt_tokens,
                    completion_tokens=usage.completion_tokens,
                    cost_usd=usage.cost_usd,
                    retries=response.retries,
                    cached=response.cached,
                )
            )
            self._log.debug(
                "request",
                row=row_id,
                latency_s=round(response.latency_s, 4),
                prompt_tokens=usage.prompt_tokens,
                completion_tokens=usage.completion_tokens,
                cost_usd=usage.cost_usd,
                retries=response.retries,
                cached=response.cached,
            )
            return response

        return ask

    @property
    def _attempt_timeout(self) -> float:
        """The per-request timeout; a backend that retries inside (litellm's Router) gets room
        for its own attempts, so our timeout never cuts its retries short."""
        backend = self.components.backend
        if getattr(backend, "retries_inside", False):
            return self.config.timeout * (1 + int(getattr(backend, "inner_retries", 3)))
        return self.config.timeout

    async def _attempt(self, request: Request) -> Response:
        """One call to the backend: limited by the semaphore, cut by the timeout."""
        self.stats.requests += 1
        async with self._limit:
            t0 = time.perf_counter()
            async with asyncio.timeout(self._attempt_timeout):
                response = await self.components.backend.complete(request, self.images)
        if not response.latency_s:
            response.latency_s = time.perf_counter() - t0
        return response

    def _wait_s(self, exc: BaseException | None, failed_attempts: int) -> float:
        """Seconds to wait after ``failed_attempts`` failures: Retry-After when the server sent
        one, else exponential backoff with jitter scaled to ``initial_wait``."""
        retry_after = getattr(exc, "retry_after", None)
        if isinstance(retry_after, (int, float)) and not isinstance(retry_after, bool) and retry_after >= 0:
            return min(float(retry_after), MAX_RETRY_AFTER_S)
        policy = self.config.retry
        backoff = policy.initial_wait * 2 ** (failed_attempts - 1) + random.uniform(0, policy.initial_wait)
        return min(backoff, policy.max_wait)

    def _log_retry(self, row_id: str, exc: BaseException, failed_attempts: int, wait_s: float) -> None:
        self._log.info(
            "retry",
            row=row_id,
            attempt=failed_attempts,
            error_type=error_type_of(exc),
            error=self._redactor.text(f"{type(exc).__name__}: {exc}"),
            wait_s=round(wait_s, 3),
        )

    async def _call_backend(self, request: Request, row_id: str) -> Response:
        """One model call, retried on transient failures only (never on a 4xx).

        The first attempt runs bare (the common case pays nothing for retries); after a
        transient failure, tenacity drives the remaining attempts. A backend that retries
        inside (litellm's Router) gets one attempt: its failure, our timeout included, is final.
        """
        policy = self.config.retry
        attempts = 1
        try:
            try:
                response = await self._attempt(request)
            except Exception as first:
                if policy.attempts == 1 or not is_transient(first) or getattr(self.components.backend, "retries_inside", False):
                    raise
                wait_s = self._wait_s(first, 1)
                self._log_retry(row_id, first, 1, wait_s)
                await asyncio.sleep(wait_s)

                def before_sleep(state: Any) -> None:
                    self._log_retry(row_id, state.outcome.exception(), state.attempt_number + 1, state.upcoming_sleep)

                async for attempt in AsyncRetrying(
                    stop=stop_after_attempt(policy.attempts - 1),
                    wait=lambda state: self._wait_s(state.outcome.exception(), state.attempt_number + 1),
                    retry=retry_if_exception(is_transient),
                    before_sleep=before_sleep,
                    reraise=True,
                ):
                    with attempt:
                        attempts += 1
                        response = await self._attempt(request)
        except Exception as exc:
            self.stats.retries += attempts - 1
            kind = error_type_of(exc)
            message = self._redactor.text(f"{type(exc).__name__}: {exc}" + (f" (after {attempts} attempts)" if attempts > 1 else ""))
            if kind == "backend_exception":
                # Not an API failure: a bug in the backend plugin; keep its traceback in the log.
                self._log.error("backend_exception", row=row_id, error=message, traceback=self._redactor.text(traceback.format_exc()))
            raise InfraFailure(kind, message, attempts) from exc
        response.retries = attempts - 1
        self.stats.retries += attempts - 1
        return response

    async def _read_frames(self, instance: Instance) -> None:
        """Read the instance's new frames into the image store in a worker thread, once each.

        Strategies read images synchronously; a new house's 30 frames read on the event loop
        would stall every request in flight. Here the frames not yet in the store are read in
        one thread call (however many workers need them at once), and the strategy then finds
        them in the store. A file that cannot be read is left for the strategy to meet (and
        report) itself.
        """
        frames = instance.frames
        frames_id = id(frames)
        if self._frames_read.get(frames_id) is frames:
            return  # A/B instances of a house share one frames tuple: checked once, not per key
        images = self.images
        # The other keys of a house arrive while its frames are being read: they wait for the
        # reads the first one found, without looking at every frame again.
        known = self._frames_waits.get(frames_id)
        if known is not None and known[0] is frames and not all(w.done() for w in known[1]):
            waits = known[1]
        else:
            reads = self._reads
            new = [f.file for f in frames if f.file not in reads and not images.knows_file(f.file)]
            if new:
                task = asyncio.ensure_future(asyncio.to_thread(_read_files, images, new))
                for path in new:
                    reads[path] = task
                task.add_done_callback(lambda _t, paths=new: [reads.pop(p, None) for p in paths])
            waits = {reads[f.file] for f in frames if f.file in reads}
            if waits:
                # Holding the tuple keeps its id from being reused while the entry lives.
                self._frames_waits[frames_id] = (frames, waits)
        if waits:
            await asyncio.gather(*waits)
            if self._frames_read.get(frames_id) is frames:
                return  # another key of the house checked them meanwhile
        if all(images.knows_file(f.file) for f in frames):
            self._frames_read[frames_id] = frames
            self._frames_waits.pop(frames_id, None)

    async def _solve(self, instance: Instance, run: int) -> ResultRow:
        """Everything for one key, ending in its row (never raises for plugin or API failures)."""
        comps = self.components
        iid = instance.id
        key = row_key(iid, run)
        started = utc_now()
        t0 = time.perf_counter()
        exchanges: list[ExchangeRecord] = []
        parse: ParsedAnswer | None = None
        scores: dict[str, dict[str, Any]] = {}
        prediction = Prediction()
        error_type = error_message = None
        try:
            await self._read_frames(instance)
            turns = await comps.strategy.solve(instance, self._make_ask(run, exchanges, key), self.images)
            request, response = turns[-1]
            if response.by_strategy:  # worked out by the strategy, not asked: the row keeps it last
                exchanges.append(ExchangeRecord(request_hash=request.content_hash(), raw=response.text))
            parse = self._parse(comps.parser, response.text, request, key)
            if parse.answered:
                status = RowStatus.ANSWERED
                prediction = _prediction(instance, parse)
                for name, scorer in comps.scorers.items():
                    scores[name] = self._score(name, scorer, instance, parse, key)
            else:
                status = RowStatus.PARSE_ERROR
        except InfraFailure as exc:
            status, error_type, error_message = RowStatus.INFRA_ERROR, exc.error_type, exc.message
        except Exception as exc:  # a strategy bug or unreadable image must not end the run
            status, error_type = RowStatus.INFRA_ERROR, "strategy_error"
            error_message = self._redactor.text(f"{type(exc).__name__}: {exc}")
            self._log.error("strategy_error", row=key, error=error_message, traceback=self._redactor.text(traceback.format_exc()))
        prompt = sum(e.prompt_tokens for e in exchanges if e.prompt_tokens is not None) if exchanges else None
        completion = sum(e.completion_tokens for e in exchanges if e.completion_tokens is not None) if exchanges else None
        costs = [e.cost_usd for e in exchanges if e.cost_usd is not None]
        retries = sum(e.retries for e in exchanges)
        return ResultRow.model_construct(
            key=key,
            instance_id=iid,
            house_id=instance.house_id,
            pair_id=instance.pair_id,
            direction=instance.direction.value,
            condition=instance.condition.value,
            run=run,
            sentence=instance.sentence,
            backend=self._names[0],
            strategy=self._names[1],
            parser=self._names[2],
            config_hash=self.config_hash,
            status=status,
            exchanges=exchanges,
            parse=parse,
            prediction=prediction,
            scores=scores,
            error_type=error_type,
            error_message=error_message,
            latency_s=time.perf_counter() - t0,
            prompt_tokens=prompt,
            completion_tokens=completion,
            cost_usd=sum(costs) if costs else None,
            retries=retries,
            started_at=started,
            finished_at=utc_now(),
        )

    def _parse(self, parser: Parser, text: str, request: Request, key: str) -> ParsedAnswer:
        try:
            return parser.parse(text, request.answer)
        except Exception as exc:  # parsers must not raise; if one does, the row is a parse error
            self._log.error("parser_exception", row=key, error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
            return ParsedAnswer(status=ParseStatus.UNPARSEABLE, reason=f"parser raised {type(exc).__name__}: {exc}")

    def _score(self, name: str, scorer: Scorer, instance: Instance, parse: ParsedAnswer, key: str) -> dict[str, Any]:
        try:
            return scorer.score(instance, parse, self.dataset)
        except Exception as exc:
            self._log.error("scorer_exception", row=key, scorer=name, error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
            return {"error": f"{type(exc).__name__}: {exc}"}

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
        self._digests[row.key] = digest(row)
        s = self.stats
        s.rows_written += 1
        s.statuses[row.status.value] += 1
        if row.prompt_tokens:
            s.prompt_tokens += row.prompt_tokens
        if row.completion_tokens:
            s.completion_tokens += row.completion_tokens
        if row.cost_usd:
            s.cost_usd += row.cost_usd
        if row.status is RowStatus.INFRA_ERROR:
            self._log.warning("infra_error", row=row.key, error_type=row.error_type, error=row.error_message)
        self.progress.advance(row.status.value)
        if self._observed:
            self.host.hooks.instance_done(str(self.run_dir), row)

    def _report_dataset_problems(self) -> None:
        """Say which houses or pairs loading skipped (file, JSON path, sentence): never silently."""
        problems = list(getattr(self.dataset, "problems", ()) or ())
        for p in problems:
            if hasattr(p, "file"):
                self._log.warning("dataset_problem", file=p.file, path=p.json_path, problem=p.message)
            else:
                self._log.warning("dataset_problem", problem=str(p))
        if problems:
            self._log.warning(
                "dataset_problems",
                count=len(problems),
                hint="the houses or pairs named above were skipped; `povagent validate` lists every problem, --strict stops instead",
            )

    # -- the whole run -------------------------------------------------------------------------
    async def run(self) -> RunResult:
        """Run every pending key; write the run folder; return the summary."""
        t_start = time.perf_counter()
        config = self.config
        if self.dataset is None:
            self.dataset = prepare_dataset(config)
        instances = select_instances(self.dataset, config)
        if not instances:
            raise ConfigError(f"no instances selected from {config.dataset.root} (check instances: conditions, directions, houses)")
        check_scorers = getattr(self.dataset, "check_scorers", None)  # a real-world set has no 3D GT
        if check_scorers is not None:
            check_scorers([s.name for s in config.scorers])
        runs = config.run_indices
        wanted = {row_key(i.id, r) for i in instances for r in runs}
        # Plugins check their options first: a rejected option (a literal API key, say) fails
        # before anything is written to the run folder.
        self.components = create_components(config, self.host)
        self.run_dir.mkdir(parents=True, exist_ok=True)
        with folder_lock(self.run_dir):
            return await self._run_in_folder(instances, runs, wanted, t_start)

    async def _run_in_folder(self, instances: list[Instance], runs: list[int], wanted: set[str], t_start: float) -> RunResult:
        """The run proper, with the run folder locked against a second process."""
        config = self.config
        done = self._check_folder(wanted) & wanted
        pending = [(inst, r) for inst in instances for r in runs if row_key(inst.id, r) not in done]
        (self.run_dir / CONFIG).write_text(dump_pipeline(config, self._redactor), encoding="utf-8")

        self._identity = identity_json(self.components.backend.identity())
        self._names = (config.backend.name, config.strategy.name, config.parser.name)  # type: ignore[union-attr]
        self._limit = asyncio.Semaphore(config.concurrency)
        self._observed = bool(self.host.hooks.active)
        cache_path = config.cache_path()
        if self._cache is None and cache_path is not None and getattr(self.components.backend, "cacheable", True):
            self._cache = ResponseCache(cache_path)
        self._log = RunLog(self.run_dir / LOG, console=self.console_log, redactor=self._redactor, run=str(self.run_dir))
        # Before each batch of rows is written (in the journal's thread, off the event loop) the
        # log is pushed to the OS and queued answers are stored in the cache: after a kill, every
        # durable row has its request events in log.jsonl and its answers in the cache.
        self._journal = RowJournal(self.run_dir / RESULTS, self._reported, before_write=self._before_rows)
        self._report_dataset_problems()

        self._log.info("run_start", n_total=len(wanted), n_pending=len(pending), config_hash=self.config_hash,
                       backend=self._names[0], strategy=self._names[1], parser=self._names[2])
        self.host.hooks.run_start(str(self.run_dir), config.resolved_dict(), len(pending), len(wanted))
        self.progress.start(len(wanted), len(wanted) - len(pending))
        interrupted = True
        try:
            work = iter(pending)

            async def worker() -> None:
                # Workers pull keys in dataset order: bounded memory, and a house's frames
                # stay hot in the image store while its keys are in flight.
                for instance, run in work:
                    self._journal.submit(await self._solve(instance, run))
                    # Let the committer run even when the backend answers without suspending
                    # (offline baselines): rows become durable as they finish, not at the end.
                    await self._journal.backpressure()

            try:
                async with asyncio.TaskGroup() as group:
                    for _ in range(min(config.concurrency, len(pending))):
                        group.create_task(worker())
                await self._journal.drain()
            except BaseException as exc:
                failed = self._journal.error
                if failed is not None:  # a full disk, a lost mount: the user's to fix, not a bug
                    raise ResultsError(
                        f"{self.run_dir / RESULTS}: cannot write rows ({type(failed).__name__}: {failed}); the rows "
                        f"already written are kept: fix that and run the same command again to resume"
                    ) from failed
                if isinstance(exc, BaseExceptionGroup) and len(exc.exceptions) == 1:
                    raise exc.exceptions[0]  # one worker's bug: its own traceback, not a group's
                raise
            interrupted = False
        finally:
            self.progress.stop()
            self.stats.wall_s = time.perf_counter() - t_start
            await self._journal.aclose()
            self._flush_cache()  # answers of keys that did not finish (an interrupted run)
            self.stats.fsyncs, self.stats.fsync_s = self._journal.fsyncs, self._journal.fsync_s
            summary = self.write_summary(instances, runs, interrupted)
            self._log.info("run_end", interrupted=interrupted, **{k: v for k, v in self.stats.as_dict().items() if k != "statuses"})
            self.host.hooks.run_end(str(self.run_dir), summary)
            self._log.close()
            try:
                await self.components.backend.aclose()
            finally:
                if self._own_cache and self._cache is not None:
                    self._cache.close()
        return RunResult(self.run_dir, summary, self.stats, len(wanted), len(pending), interrupted)

    def write_summary(self, instances: list[Instance], runs: list[int], interrupted: bool) -> dict[str, Any]:
        """Write ``summary.json``: official breakdown over the selected keys, plus run stats."""
        summary = summarize_digests(self._digests.values(), {row_key(i.id, r) for i in instances for r in runs})
        summary["pipeline"] = {
            "backend": self._names[0],
            "strategy": self._names[1],
            "parser": self._names[2],
            "scorers": list(self.components.scorers),
            "config_hash": self.config_hash,
        }
        summary["complete"] = summary["rows"]["missing"] == 0
        summary["interrupted"] = interrupted
        summary["session"] = self.stats.as_dict()
        summary["images"] = {**dataclasses.asdict(self.images.stats), "distinct": self.images.distinct}
        _write_json(self.run_dir / SUMMARY, summary)
        return summary


def _read_files(images: ImageStore, paths: list[Path]) -> None:
    """Add image files to the store (in a worker thread); unreadable ones are skipped here."""
    for path in paths:
        try:
            images.add_file(path)
        except Exception:  # the strategy meets the same error and the row records it
            pass


def _prediction(instance: Instance, parse: ParsedAnswer) -> Prediction:
    image_path = None
    sel = parse.selected_image
    if instance.condition.uses_exploration_frames and sel is not None and 0 <= sel < len(instance.frames):
        image_path = instance.frames[sel].image_path
    return Prediction.model_construct(selected_image=sel, image_path=image_path, x=parse.x, y=parse.y)


def scored_row(row: ResultRow, scorer: str = "official") -> ScoredRow:
    """The fields a summary needs, from a row's official score (non-answers count as such)."""
    score = row.scores.get(scorer) or {}
    answered = row.status is RowStatus.ANSWERED and bool(score.get("answered"))
    return ScoredRow(
        condition=row.condition,
        direction=row.direction,
        answered=answered,
        l2=score.get("l2") if answered else None,
        gt_in_frame=score.get("gt_in_frame") if answered else None,
        l2_strict=score.get("l2_strict") if answered else None,
    )


@dataclass(frozen=True, slots=True)
class RowDigest:
    """The few fields of a row that ``summary.json`` needs.

    The runner keeps one per key (rows of earlier sessions read once at resume, its own rows as
    they become durable), so writing the summary never parses ``results.jsonl`` again.
    """

    key: str
    run: int
    status: str
    scored: ScoredRow
    has_success: bool
    success: Any
    answered: bool
    prompt_tokens: int | None
    completion_tokens: int | None
    cost_usd: float | None
    retries: int


def digest(row: ResultRow) -> RowDigest:
    """The summary fields of one row."""
    success = row.scores.get("success")
    return RowDigest(
        key=row.key,
        run=row.run,
        status=RowStatus(row.status).value,
        scored=scored_row(row),
        has_success=success is not None,
        success=(success or {}).get("success"),
        # a row the runner never scored (parse or infra error) is unanswered
        answered=(success or {}).get("answered") is True,
        prompt_tokens=row.prompt_tokens,
        completion_tokens=row.completion_tokens,
        cost_usd=row.cost_usd,
        retries=row.retries,
    )


def summarize_digests(digests: Iterable[RowDigest], keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction, per run too) of row digests.

    ``keys`` is the run's selection (``rows`` then counts missing keys); digests of other keys
    are left out.
    """
    rows = [d for d in digests if keys is None or d.key in keys]
    scored = [d.scored for d in rows]
    out = breakdown(scored)
    if any(d.has_success for d in rows):
        from povagent.dataset.realworld import success_breakdown

        out["success"] = success_breakdown(
            {"condition": d.scored.condition, "direction": d.scored.direction, "success": d.success, "answered": d.answered}
            for d in rows
        )
    per_run: dict[int, list[ScoredRow]] = {}
    for d in rows:
        per_run.setdefault(d.run, []).append(d.scored)
    out["per_run"] = {str(k): summarize(v) for k, v in sorted(per_run.items())}
    statuses = Counter(d.status for d in rows)
    costs = [d.cost_usd for d in rows if d.cost_usd is not None]
    out["rows"] = {
        "total": len(keys) if keys is not None else len(rows),
        "done": len(rows),
        "missing": (len(keys) - len(rows)) if keys is not None else 0,
        **{s.value: statuses.get(s.value, 0) for s in RowStatus},
    }
    out["usage"] = {
        "prompt_tokens": sum(d.prompt_tokens or 0 for d in rows),
        "completion_tokens": sum(d.completion_tokens or 0 for d in rows),
        "cost_usd": sum(costs) if costs else None,
        "retries": sum(d.retries for d in rows),
    }
    return out


def summarize_run(results: Path, keys: set[str] | None = None) -> dict[str, Any]:
    """Breakdown (overall / per condition / per direction) of a results file, per run too.

    ``keys`` restricts it to a run's selection; ``rows`` counts statuses and missing keys.
    When a key repeats, its last row counts.
    """
    by_key: dict[str, RowDigest] = {}
    for row in iter_rows(results):
        if keys is None or row.key in keys:
            by_key[row.key] = digest(row)
    return summarize_digests(by_key.values(), keys)


def _write_json(path: Path, data: Mapping[str, Any]) -> None:
    import json

    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(data, indent=2, default=str) + "\n", encoding="utf-8")
    os.replace(tmp, path)


async def run_pipeline_async(config: PipelineConfig, **kwargs: Any) -> RunResult:
    """Run a pipeline inside an existing event loop (see :class:`PipelineRun` for options)."""
    return await PipelineRun(config, **kwargs).run()


def run_pipeline(config: PipelineConfig, **kwargs: Any) -> RunResult:
    """Run a pipeline to completion (resuming from its folder); see :class:`PipelineRun`."""
    return asyncio.run(run_pipeline_async(config, **kwargs))


def pending_keys(config: PipelineConfig, dataset: Dataset) -> tuple[int, int, list[tuple[Instance, int]]]:
    """``(n_total, n_done, pending)`` for a pipeline, without running anything (dry runs)."""
    instances = select_instances(dataset, config)
    runs = config.run_indices
    wanted = {row_key(i.id, r) for i in instances for r in runs}
    done: set[str] = set()
    for row in iter_rows(Path(config.output) / RESULTS):
        if row.key in wanted:
            done.add(row.key)
    pending = [(i, r) for i in instances for r in runs if row_key(i.id, r) not in done]
    return len(wanted), len(done), pending


def ensure_dataset(config: PipelineConfig, loaded: dict[Any, Dataset] | None = None) -> Dataset:
    """The config's dataset, loaded once per folder (and strictness) when ``loaded`` is shared
    (sweeps)."""
    key = (Path(config.dataset.root).resolve(), config.dataset.strict)
    if loaded is not None and key in loaded:
        return loaded[key]
    ds = prepare_dataset(config)
    if loaded is not None:
        loaded[key] = ds
    return ds

