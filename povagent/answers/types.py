"""Answer types: what kind of value a parser produces, registered like any plugin.

A point in one of the images shown is one answer type among others (a choice label, later a box
or a number): each is an :class:`AnswerType` a plugin contributes through the
``register_answer_types`` hook, the built-in ``point`` exactly as a third party's would be
(``povagent_plugins.answers.point``). A strategy names the type it asks for
(``Strategy.answer_type``), a parser the types it reads (``Parser.answer_types``); a pipeline
whose strategy asks for a type no plugin registers, or that its parser does not read, is refused
at load (:func:`povagent.config.plugin_checks.parser_misfit`).

Only the description of a type lives here; nothing here reads files or knows a plugin.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping

if TYPE_CHECKING:
    from povagent.answers.spec import ParsedAnswer
    from povagent.dataset.instances import Instance


@dataclass(frozen=True)
class AnswerType:
    """One kind of answer: its name, the JSON Schema of its value, how a parse gives that value,
    how the gold value is read from an instance, and how a row shows a value."""

    name: str
    description: str
    #: The JSON Schema of the value (:attr:`value_of`'s result).
    value_schema: Mapping[str, Any]
    #: The typed value of a parse that answered (``None``: no value).
    value_of: Callable[[ParsedAnswer], dict[str, Any] | None]
    #: The gold value of an instance, as the type's scorers compare against it.
    gold: Callable[[Instance], Any]
    #: How a row shows a value, in one line.
    show: Callable[[Mapping[str, Any]], str]
    #: The answer type this one refines (its value has that type's shape, e.g. a point read as
    #: marking another object): it answers instances asking either (``None``: only its own).
    refines: str | None = None
    #: Further answer types whose instances this one answers (a set mixing option and number
    #: questions, VSI-Bench's, is answered by a type that answers both).
    also_answers: tuple[str, ...] = ()
    #: The strategy a pipeline gets when its set asks this type and it names none (``None``:
    #: the pipeline's own default, POVBench's ``basic``).
    default_strategy: str | None = None
    #: The scorers a pipeline gets when its set asks this type and it names none (empty: the
    #: pipeline's own default, POVBench's ``official``); a set's own scorer comes first.
    default_scorers: tuple[str, ...] = ()

    def answers(self, asked: str) -> bool:
        """Whether an answer of this type answers an instance asking for ``asked``."""
        return asked in (self.name, self.refines) or asked in self.also_answers


def answer_type_misfit(strategy: str, answer_type: AnswerType, instances: Iterable[Instance]) -> str | None:
    """One line refusing a pipeline whose strategy (``strategy``, asking ``answer_type``) cannot
    answer the first instance asking another type, or ``None`` when it answers them all: a
    choice set asked for points would score every row as a parse error, silently."""
    for instance in instances:
        if not answer_type.answers(instance.answer_type):
            return (
                f"strategy {strategy!r} asks for a {answer_type.name!r} answer, but instance {instance.id} asks for "
                f"a {instance.answer_type!r} answer: choose a strategy that asks for {instance.answer_type!r}"
            )
    return None
