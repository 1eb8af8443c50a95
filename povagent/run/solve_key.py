"""The solve step of one key: ask the model through the strategy, hand the final answer to the
score step (:mod:`povagent.run.score_step`, which ``rescore`` shares), and build the key's row.

:class:`KeySolver` holds what that step needs from the run (its components and their names,
the request path, the image store, the log); :meth:`KeySolver.solve` never raises for a plugin
or API failure: the row records it (an ``infra_error`` row, a parse error, a scorer's
``{"error": ...}``). The run around it (planning keys, the fan-out, the journal, the summary)
is :mod:`povagent.run.runner`'s.
"""

from __future__ import annotations

import dataclasses
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Awaitable, Callable, Iterator

from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance, row_key
from povagent.dataset.set_interface import EvaluationSet
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import InfraFailure
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.exchange.usage_totals import usage_sums
from povagent.files.logs import RunLog
from povagent.files.redaction import Redactor
from povagent.files.timestamps import utc_now
from povagent.results.model_construct import construct
from povagent.results.output_check import checking
from povagent.results.plugin_errors import error_text
from povagent.results.rows import Prediction, ResultRow, RowStatus
from povagent.results.transcript import RowTranscript
from povagent.results.upgrade import ROW_FORMAT
from povagent.run.components import ComponentNames, Components
from povagent.run.score_lane import ScoreLane
from povagent.run.score_step import AnswerScoring, ScoredAnswer, question_category, question_main_category


@dataclass
class Asked:
    """One key after its strategy ran: the final request and answer, or why there is none."""

    instance: Instance
    run: int
    key: str
    started: str
    t0: float
    transcript: RowTranscript
    request: Request | None = None
    response: Response | None = None
    error_type: str | None = None
    error_message: str | None = None
    #: retries of a request that never got an answer (no exchange holds them)
    failed_retries: int = 0


@dataclass
class KeySolver:
    """What solving one key needs from its run."""

    components: Components
    names: ComponentNames
    #: ``(model, profile)`` of the backend, as rows name them.
    model: tuple[str, str | None]
    config_hash: str
    path: RequestPath
    images: ImageStore
    dataset: EvaluationSet | None
    log: RunLog
    redactor: Redactor
    #: Reads an instance's frames into the image store before its strategy runs.
    read_frames: Callable[[Instance], Awaitable[None]]
    #: The system's name the pipeline gave (``label:``), carried by every row.
    label: str | None = None
    #: The worker threads answers are parsed and scored in (never the event loop).
    lane: ScoreLane = field(default_factory=ScoreLane)

    def make_ask(self, run: int, transcript: RowTranscript, row_id: str) -> Callable[[Request], Any]:
        path = self.path

        async def ask(request: Request) -> Response:
            if request.run != run:
                # Offline baselines seed by run index; the cache key adds the run too.
                request = dataclasses.replace(request, run=run)
            response = await path.send(request, label=row_id)
            usage = response.usage
            transcript.record(
                request,
                raw=response.text,
                latency_s=response.latency_s,
                prompt_tokens=usage.prompt_tokens,
                completion_tokens=usage.completion_tokens,
                cost_usd=usage.cost_usd,
                retries=response.retries,
                cached=response.cached,
            )
            self.log.debug(
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

    async def solve(self, instance: Instance, run: int) -> ResultRow:
        """Everything for one key, ending in its row (never raises for plugin or API failures)."""
        asked = await self.ask(instance, run)
        if asked.response is None:
            return self.row(asked, None)
        try:
            # parsed and scored in a worker thread: a slow plugin rule never stalls the run's other keys
            scored: ScoredAnswer | Exception = await self.lane.call(self._score, asked)
        except Exception as exc:  # a strategy bug must not end the run
            scored = exc
        return self.row(asked, scored)

    async def solve_chunk(self, keys: Iterator[tuple[Instance, int]], most: int, within_s: float) -> list[tuple[Instance, ResultRow]]:
        """The next keys of ``keys`` and their rows, for a backend answering in this process
        (:attr:`~povagent.interfaces.Backend.answers_in_process`): up to ``most`` keys, fewer
        once ``within_s`` seconds have gone, each asked in turn on the event loop (no task
        each), then every answer parsed and scored in one call of a worker thread. A row is
        what :meth:`solve` would make of its key; an empty list: ``keys`` has run out."""
        asked: list[Asked] = []
        until = time.perf_counter() + within_s
        for instance, run in keys:
            asked.append(await self.ask(instance, run))
            if len(asked) >= most or time.perf_counter() >= until:
                break
        answered = [a for a in asked if a.response is not None]
        scored = iter(await self.lane.call(self._score_all, answered) if answered else ())
        return [(a.instance, self.row(a, None if a.response is None else next(scored))) for a in asked]

    async def ask(self, instance: Instance, run: int) -> Asked:
        """One key's exchanges with the model through the strategy, ending in its final answer or
        in why there is none (never raises for plugin or API failures)."""
        key = row_key(instance.id, run)
        asked = Asked(instance, run, key, utc_now(), time.perf_counter(), RowTranscript())
        try:
            await self.read_frames(instance)
            turns = await self.components.strategy.solve(instance, self.make_ask(run, asked.transcript, key), self.images)
            request, response = turns[-1]
            if response.by_strategy:  # worked out by the strategy, not asked: the row keeps it last
                asked.transcript.record(request, raw=response.text)
            asked.request, asked.response = request, response
        except InfraFailure as exc:
            asked.error_type, asked.error_message, asked.failed_retries = exc.error_type, exc.message, exc.retries
        except Exception as exc:  # a strategy bug or unreadable image must not end the run
            self._strategy_error(asked, exc)
        return asked

    def _score(self, asked: Asked) -> ScoredAnswer:
        assert asked.request is not None and asked.response is not None
        return self.scoring(asked.key).score_answer(asked.instance, asked.request.answer, asked.response.text)

    def _score_all(self, answered: list[Asked]) -> list[ScoredAnswer | Exception]:
        """Each answer scored (in a worker thread); a call that raises stands for its own key only."""
        done: list[ScoredAnswer | Exception] = []
        scoring_key = [""]
        score_answer = self._scoring(lambda: scoring_key[0]).score_answer  # made once a chunk, not once a key
        for asked in answered:
            assert asked.request is not None and asked.response is not None
            scoring_key[0] = asked.key
            try:
                done.append(score_answer(asked.instance, asked.request.answer, asked.response.text))
            except Exception as exc:
                done.append(exc)
        return done

    def _strategy_error(self, asked: Asked, exc: Exception) -> None:
        asked.error_type = "strategy_error"
        asked.error_message = self.redactor.text(f"{type(exc).__name__}: {exc}")
        trace = "".join(traceback.format_exception(exc))
        self.log.error("strategy_error", row=asked.key, error=asked.error_message, traceback=self.redactor.text(trace))

    def row(self, asked: Asked, scored: ScoredAnswer | Exception | None) -> ResultRow:
        """The key's row: its exchanges, and its scored answer (``None``: no answer; an exception:
        parsing or scoring failed outside the plugins' own guards, recorded as a strategy error)."""
        instance, run = asked.instance, asked.run
        parse: ParsedAnswer | None = None
        scores: dict[str, dict[str, Any]] = {}
        official_reading = None
        if isinstance(scored, ScoredAnswer):
            parse, prediction = scored.parse, scored.prediction
            scores, official_reading = scored.scores, scored.official_reading
        else:
            prediction = Prediction()
            if scored is not None:
                self._strategy_error(asked, scored)
        status = scored.status if isinstance(scored, ScoredAnswer) else RowStatus.INFRA_ERROR
        exchanges = asked.transcript.exchanges
        # the sums only, no UsageTotals made a key
        prompt_tokens, completion_tokens, cost_usd, retries = usage_sums(exchanges, unstated_tokens=0 if exchanges else None)
        return construct(ResultRow,
            format_version=ROW_FORMAT,
            key=asked.key,
            instance_id=instance.id,
            house_id=instance.house_id,
            pair_id=instance.pair_id,
            direction="" if instance.direction is None else instance.direction.value,  # an external item has neither
            condition="" if instance.condition is None else instance.condition.value,
            run=run,
            sentence=instance.sentence,
            backend=self.names.backend,
            model=self.model[0],
            profile=self.model[1],
            strategy=self.names.strategy,
            parser=self.names.parser,
            label=self.label,
            config_hash=self.config_hash,
            status=status,
            exchanges=exchanges,
            parse=parse,
            prediction=prediction,
            scores=scores,
            error_type=asked.error_type,
            error_message=asked.error_message,
            latency_s=time.perf_counter() - asked.t0,
            prompt_tokens=prompt_tokens,
            completion_tokens=completion_tokens,
            cost_usd=cost_usd,
            retries=retries + asked.failed_retries,
            started_at=asked.started,
            finished_at=utc_now(),
            official_reading=official_reading,
            category=question_category(instance),
            main_category=question_main_category(instance),
        )

    def scoring(self, key: str) -> AnswerScoring:
        """The score step for key ``key``: a plugin that raises is logged with its traceback and
        its failure recorded in the row (see :mod:`povagent.results.plugin_errors`)."""
        return self._scoring(lambda: key)

    def _scoring(self, key_of: Callable[[], str]) -> AnswerScoring:
        """:meth:`scoring` for the key ``key_of()`` names when a plugin raises (a chunk's one
        score step serves each of its keys in turn)."""
        comps = self.components

        def parser_raised(exc: BaseException) -> None:
            self.log.error("parser_exception", row=key_of(), error=error_text(exc), traceback=traceback.format_exc())

        def scorer_raised(name: str, exc: BaseException) -> None:
            self.log.error("scorer_exception", row=key_of(), scorer=name, error=error_text(exc), traceback=traceback.format_exc())

        return AnswerScoring(
            comps.parser,
            comps.scorers,
            self.dataset,
            comps.official_parser,
            comps.official_parser_name,
            parser_raised,
            scorer_raised,
            comps.answer_type,
            checked=checking(),  # asked once a chunk of answers, not once each
        )
