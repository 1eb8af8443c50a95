"""An answer session: the runner's own run, with a person's order and the desk told of saved rows.

:class:`AnswerSession` is a :class:`~povagent.run.runner.PipelineRun`: the same journal, the
same parser and scorers, the same folder rules, so a person's rows are rows like a model's. It
changes two things only: the pending keys are taken in the annotator's order
(:func:`~povagent.annotate.order.annotator_order`, computed over every key, so a resumed
session continues the order it began), and each durable row is reported to the desk, which
shows the next question only then.
"""

from __future__ import annotations

from typing import Any

from povagent.annotate.desk import AnswerDesk
from povagent.annotate.order import annotator_order
from povagent.config.models import PipelineConfig
from povagent.dataset.instances import Instance
from povagent.results.rows import ResultRow
from povagent.run.run_result import RunResult
from povagent.run.runner import PipelineRun


class AnswerSession(PipelineRun):
    """One annotator's pipeline run (see the module docstring)."""

    def __init__(self, config: PipelineConfig, desk: AnswerDesk, *, seed: int = 0, pairs_apart: bool = True, **kwargs: Any) -> None:
        super().__init__(config, **kwargs)
        self.desk = desk
        self.seed, self.pairs_apart = seed, pairs_apart
        self._selected: list[Instance] = []

    async def _run_in_folder(self, instances: list[Instance], t_start: float) -> RunResult:
        self._selected = instances
        return await super()._run_in_folder(instances, t_start)

    async def _fan_out(self, pending: list[tuple[Instance, int]]) -> None:
        every = [(i, r) for i in self._selected for r in self.config.run_indices]
        wanted = {(i.id, r) for i, r in pending}
        order = annotator_order(every, self.desk.annotator, self.seed, pairs_apart=self.pairs_apart)
        self.desk.total = len(every)
        self.desk.done = len(every) - len(pending)
        await super()._fan_out([(i, r) for i, r in order if (i.id, r) in wanted])

    def _reported(self, row: ResultRow) -> None:
        super()._reported(row)
        self.desk.row_saved()
