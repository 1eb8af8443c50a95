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
from typing import Any, Awaitable, Callable

from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance, row_key
from povagent.dataset.set_interface import EvaluationSet
from povagent.engine.request_path import RequestPath
from povagent.engine.retry import InfraFailure
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response
from povagent.exchange.usage_totals import UsageTotals
from povagent.files.logs import RunLog
from povagent.files.redaction import Redactor
from povagent.results.model_construct import construct
from povagent.results.plugin_errors import error_text
from povagent.results.rows import Prediction, ResultRow, RowStatus, utc_now
from povagent.results.transcript import RowTranscript
from povagent.results.upgrade import ROW_FORMAT
from povagent.run.components import ComponentNames, Components
from povagent.run.score_lane import ScoreLane
from povagent.run.score_step import AnswerScoring, question_category, question_main_category


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
        comps = self.components
        iid = instance.id
        key = row_key(iid, run)
        started = utc_now()
        t0 = time.perf_counter()
        transcript = RowTranscript()
        exchanges = transcript.exchanges
        parse: ParsedAnswer | None = None
        scores: dict[str, dict[str, Any]] = {}
        prediction = Prediction()
        official_reading = None
        error_type = error_message = None
        failed_retries = 0  # retries of a request that never got an answer (no exchange holds them)
        try:
            await self.read_frames(instance)
            turns = await comps.strategy.solve(instance, self.make_ask(run, transcript, key), self.images)
            request, response = turns[-1]
            if response.by_strategy:  # worked out by the strategy, not asked: the row keeps it last
                transcript.record(request, raw=response.text)
            # parsed and scored in a worker thread: a slow plugin rule never stalls the run's other keys
            scored = await self.lane.call(self.scoring(key).score_answer, instance, request.answer, response.text)
            parse, status, prediction = scored.parse, scored.status, scored.prediction
            scores, official_reading = scored.scores, scored.official_reading
        except InfraFailure as exc:
            status, error_type, error_message = RowStatus.INFRA_ERROR, exc.error_type, exc.message
            failed_retries = exc.retries
        except Exception as exc:  # a strategy bug or unreadable image must not end the run
            status, error_type = RowStatus.INFRA_ERROR, "strategy_error"
            error_message = self.redactor.text(f"{type(exc).__name__}: {exc}")
            self.log.error("strategy_error", row=key, error=error_message, traceback=self.redactor.text(traceback.format_exc()))
        spent = UsageTotals.of(exchanges, unstated_tokens=0 if exchanges else None)
        return construct(ResultRow,
            format_version=ROW_FORMAT,
            key=key,
            instance_id=iid,
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
            error_type=error_type,
            error_message=error_message,
            latency_s=time.perf_counter() - t0,
            prompt_tokens=spent.prompt_tokens,
            completion_tokens=spent.completion_tokens,
            cost_usd=spent.cost_usd,
            retries=spent.retries + failed_retries,
            started_at=started,
            finished_at=utc_now(),
            official_reading=official_reading,
            category=question_category(instance),
            main_category=question_main_category(instance),
        )

    def scoring(self, key: str) -> AnswerScoring:
        """The score step for key ``key``: a plugin that raises is logged with its traceback and
        its failure recorded in the row (see :mod:`povagent.results.plugin_errors`)."""
        comps = self.components

        def parser_raised(exc: BaseException) -> None:
            self.log.error("parser_exception", row=key, error=error_text(exc), traceback=traceback.format_exc())

        def scorer_raised(name: str, exc: BaseException) -> None:
            self.log.error("scorer_exception", row=key, scorer=name, error=error_text(exc), traceback=traceback.format_exc())

        return AnswerScoring(
            comps.parser, comps.scorers, self.dataset, comps.official_parser, comps.official_parser_name, parser_raised, scorer_raised, comps.answer_type
        )
