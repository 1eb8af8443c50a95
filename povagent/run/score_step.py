"""The score step of one key: a final raw answer read and scored, the same way for every command.

``run`` gets the answer from the model (:mod:`povagent.run.solve_key`), ``rescore`` from the row
a run wrote (:mod:`povagent.run.rescore`); both hand it here, with the answer the strategy asked
for, so a row's parse, status, prediction, scores and official reading follow one set of rules:

* the instance is scored as the model saw it (:func:`instance_view`): a strategy that shows the
  first N frames is scored against those N, so an answer naming a frame it never showed is no
  frame at all (the official runner maps the index back through the frames it sent);
* an answer is ``answered`` when its parse answers, else a ``parse_error``, which is not scored
  and has no prediction;
* a lenient parser's row keeps the official reading beside it
  (:func:`~povagent.results.official_reading.read_officially`).

A second copy of these rules is how ``rescore`` once scored a run that showed fewer frames
against the whole instance. This module must not call a model, read files or write rows.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable, Mapping

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent.answers.types import AnswerType
from povagent.dataset.instances import Instance
from povagent.dataset.set_interface import EvaluationSet
from povagent.interfaces import Parser, Scorer
from povagent.results.model_construct import construct
from povagent.results.official_reading import read_officially
from povagent.results.output_check import check_answer_value
from povagent.results.plugin_errors import parse_or_unparseable, score_or_error
from povagent.results.rows import OfficialReading, Prediction, RowStatus

#: Told of an exception a parser raised: ``(exception)``.
OnParserError = Callable[[BaseException], None]
#: Told of an exception a scorer raised: ``(scorer name, exception)``.
OnScorerError = Callable[[str, BaseException], None]


def instance_view(instance: Instance, spec: AnswerSpec) -> Instance:
    """The instance as the model saw it: the first ``spec.n_frames`` frames when the answer
    names a frame among fewer than the instance has, else the instance itself."""
    n = spec.n_frames
    if spec.asks_frame and 0 < n < len(instance.frames):
        return dataclasses.replace(instance, frames=instance.frames[:n])
    return instance


def question_category(instance: Instance) -> str | None:
    """The category a row of ``instance`` records (:attr:`ResultRow.category`): its
    multiple-choice or numerical question's, or ``None`` for an instance asking neither. Recorded
    whatever the answer, so a reply naming no option counts, wrong, in its category's slice."""
    question = instance.question if instance.question is not None else instance.numeric
    return None if question is None else str(question.category or "")


def question_main_category(instance: Instance) -> str | None:
    """The broader type of ``instance``'s question category a row records
    (:attr:`ResultRow.main_category`: 3DSRBench's ``orientation``), or ``None`` where it has none."""
    question = instance.question
    return (question.main_category or None) if question is not None else None


def prediction_of(instance: Instance, parse: ParsedAnswer, answer_type: AnswerType | None = None, *, checked: bool | None = None) -> Prediction:
    """What a row records as the prediction: the frame index, its image path (A/B), the point,
    and the typed value ``answer_type`` reads from the parse (``checked``: whether tests run, as
    the caller asked it already; see :func:`~povagent.results.output_check.check_answer_value`)."""
    sel = parse.selected_image
    frame = instance.selected_frame(sel) if instance.answers_a_frame else None
    image_path = frame.image_path if frame is not None else None
    typed = answer_type.name if answer_type is not None else None
    value = answer_type.value_of(parse) if answer_type is not None else None
    if answer_type is not None and checked is not False:  # while testing: the value has the shape its type publishes
        check_answer_value(answer_type.name, answer_type.value_schema, value, instance.id, on=checked)
    return construct(Prediction, selected_image=sel, image_path=image_path, x=parse.x, y=parse.y, answer_type=typed, value=value)


@dataclass(frozen=True)
class ScoredAnswer:
    """A final answer as its row records it."""

    parse: ParsedAnswer
    status: RowStatus
    prediction: Prediction
    scores: dict[str, dict[str, Any]]
    official_reading: OfficialReading | None


@dataclass
class AnswerScoring:
    """What scoring an answer needs: the parser, the scorers, the set, the official reading's
    parser (``None`` when ``parser`` reads officially itself), what to do when a plugin raises
    (``run`` logs it and the row records it; ``rescore`` stops), and the answer type asked for."""

    parser: Parser
    scorers: Mapping[str, Scorer]
    dataset: EvaluationSet | None
    official_parser: Parser | None = None
    official_parser_name: str | None = None
    on_parser_error: OnParserError | None = None
    on_scorer_error: OnScorerError | None = None
    #: The answer type the strategy asked for: the prediction's typed value.
    answer_type: AnswerType | None = None
    #: Whether typed values are checked against their schema (tests), as the maker asked it
    #: (``None``: asked at each answer).
    checked: bool | None = None

    def score_answer(self, instance: Instance, spec: AnswerSpec, text: str) -> ScoredAnswer:
        """``text`` (the final raw answer to ``spec``) parsed and scored on ``instance`` as shown."""
        parse = parse_or_unparseable(self.parser, text, spec, self.on_parser_error)
        shown = instance_view(instance, spec)
        scores: dict[str, dict[str, Any]] = {}
        if parse.answered:
            status = RowStatus.ANSWERED
            prediction = prediction_of(shown, parse, self.answer_type, checked=self.checked)
            scores = self.scores_of(shown, parse)
        else:
            status = RowStatus.PARSE_ERROR
            prediction = Prediction()
        reading = None
        if self.official_parser is not None:  # a lenient parser: keep the official reading beside
            reading = read_officially(
                self.official_parser,
                self.official_parser_name or "",
                text,
                spec,
                parse,
                scores,
                lambda p: self.scores_of(shown, p),
            )
        return ScoredAnswer(parse, status, prediction, scores, reading)

    def scores_of(self, shown: Instance, parse: ParsedAnswer) -> dict[str, dict[str, Any]]:
        """Every scorer's fields for ``parse`` on the instance as shown."""
        return {name: score_or_error(scorer, shown, parse, self.dataset, self._told(name)) for name, scorer in self.scorers.items()}

    def _told(self, scorer: str) -> Callable[[BaseException], None] | None:
        on_error = self.on_scorer_error
        return None if on_error is None else lambda exc: on_error(scorer, exc)
