"""The povagent plugin contract: every hook a plugin may implement.

Two kinds of hooks:

* **Contribution hooks** ``register_<things>(register)``: called once per plugin, when the
  plugin host first looks a name up. The plugin calls ``register(name, factory,
  description=...)`` for each thing it contributes; the core owns the names, so a name
  registered twice is an error that names both plugins. The return value is ignored.
* **Lifecycle hooks** ``povagent_*``: called by the runner as a run progresses, for loggers and
  live dashboards. They observe; their return value is ignored and they must not raise (an
  exception in one is logged and the run goes on).

Implement them with ``@povagent.hookimpl``. No hook here is ``firstresult``: none chooses
one answer among plugins. ``docs/reference/plugins.md`` renders every hook below from this module
(``python tools/plugin_docs.py``), so a docstring here is the page's text.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Mapping

import pluggy

if TYPE_CHECKING:
    from povagent.results.rows import ResultRow

PROJECT = "povagent"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)

#: ``register(name, factory, *, description="")``: the callback contribution hooks receive.
Register = Callable[..., None]


# -- contribution hooks ------------------------------------------------------------------------
@hookspec
def register_backends(register: Register) -> None:
    """Contribute model backends: what answers a :class:`~povagent.exchange.messages.Request`.

    Called once per plugin, when the plugin host first collects registered names. For each
    backend call ``register(name, factory, description="...")``. ``factory(**options)``, with
    ``options`` the pipeline YAML's ``backend.options``, returns a
    :class:`povagent.interfaces.Backend`; a factory that rejects its options
    raises ``TypeError`` or ``ValueError`` and the user sees a message naming the backend, its
    plugin and the options. ``description`` is what ``povagent plugins`` shows (default: the
    factory's first docstring line). A backend says how it failed by raising
    :class:`~povagent.interfaces.TransientBackendError` (retried) or
    :class:`~povagent.interfaces.PermanentBackendError` (recorded at once).
    """


@hookspec
def register_strategies(register: Register) -> None:
    """Contribute prompt strategies: how a model is asked about one instance.

    Called once per plugin, when the plugin host first collects registered names. For each
    strategy call ``register(name, factory, description="...")``. ``factory(**options)``, with
    ``options`` the pipeline YAML's ``strategy.options`` (a model profile's
    ``strategy_options`` first), returns a :class:`povagent.interfaces.Strategy`, whose
    ``build(instance, images)`` returns the :class:`~povagent.exchange.messages.Request`,
    whose ``solve(instance, ask, images)`` returns every ``(Request, Response)`` exchange, the
    answer last, and whose ``plan_turns(instance, images)`` lists every turn ``solve`` takes
    before any model call (:class:`~povagent.interfaces.PlannedTurn`; a multi-turn strategy
    overrides both). Bad options: raise ``TypeError`` or ``ValueError`` in the factory.
    """


@hookspec
def register_parsers(register: Register) -> None:
    """Contribute output parsers: what reads a point out of a model's raw answer.

    Called once per plugin, when the plugin host first collects registered names. For each
    parser call ``register(name, factory, description="...")``. ``factory(**options)``, with
    ``options`` the pipeline YAML's ``parser.options``, returns a
    :class:`povagent.interfaces.Parser`, whose ``parse(text, spec)`` returns a
    :class:`~povagent.answers.spec.ParsedAnswer` and never raises: text it cannot read is a
    parse with status ``unparseable`` and a ``reason``. Every parser but ``official`` is a
    repair: the official reading is kept beside its parse in each row and summary.
    """


@hookspec
def register_scorers(register: Register) -> None:
    """Contribute scorers: what judges one parsed answer against the ground truth.

    Called once per plugin, when the plugin host first collects registered names. For each
    scorer call ``register(name, factory, description="...")``. ``factory(**options)``, with
    ``options`` those of the scorer's entry under the pipeline YAML's ``scorers:``, returns a
    :class:`povagent.interfaces.Scorer`, whose ``score(instance, answer, dataset)`` returns a
    JSON-able dict, stored in each answered row as ``scores[name]``; ``summary.json``'s
    ``scorers`` section averages its number fields and counts its true/false ones. The metrics
    its class declares (``Scorer.metrics``: :class:`povagent.scoring.metrics.Metric`) get
    ``summary.json``'s ``metrics`` section, a console table, and a report table and plot per metric.
    """


@hookspec
def register_answer_types(register: Register) -> None:
    """Contribute answer types: the kind of value a parser produces (a point, a choice label).

    Called once per plugin, when the plugin host first collects registered names. For each type
    call ``register(name, answer_type, description="...")`` where ``answer_type`` is a
    :class:`povagent.answers.types.AnswerType` (the JSON Schema of its value, how a parse gives
    the value, how the gold value is read from an instance, how a row shows a value). A strategy
    names the type it asks for (``Strategy.answer_type``) and a parser the types it reads
    (``Parser.answer_types``); a pipeline asking for a type no plugin registers is refused at load.
    """


@hookspec
def register_dataset_formats(register: Register) -> None:
    """Contribute dataset formats: what a set's files are and how they are read and scored.

    Called once per plugin, when the plugin host first collects registered names. For each
    format call ``register(key, dataset_format, description="...")`` where ``dataset_format``
    is a :class:`povagent.dataset.formats.DatasetFormat` whose ``key`` is ``key`` (what
    ``dataset.format`` and ``povagent validate --format`` name): its reader, how a problem names
    a record, its answer type, its official parser and scorer (registered plugins, checked when a
    pipeline names the format), its prompt profile, its source and licence, and its row in the
    docs' table of sets. A pipeline naming a format no plugin registers is refused at load.
    """


@hookspec
def register_model_profiles(register: Register) -> None:
    """Contribute model profiles: short names for models with their defaults (``model: NAME``).

    Called once per plugin, when the plugin host first collects registered names. For each
    profile call ``register(name, profile)`` where ``profile`` is a
    :class:`povagent.config.profiles.ModelProfile` (the litellm model string, the default
    parser, default backend and strategy options, quirks); ``name`` should be ``profile.name``.
    """


# -- contribution hooks: the active mode ----------------------------------------------------
@hookspec
def register_tools(register: Register) -> None:
    """Contribute active-mode tools: what a model may call to look around before it answers.

    Called once per plugin, when the plugin host first collects the tools (an ``active``
    episode offers every registered tool, in the order the plugins were loaded: the built-ins
    first). For each tool call ``register(name, tool)`` with ``tool`` a
    :class:`povagent.active.tools.Tool`: its description and arguments (the OpenAI function
    schema the model is offered), how its arguments are read, what it does to the episode
    (``run(state, arguments)`` returns a new pose to render, words, or the final answer), and
    how the preamble and the docs describe it. The set offered is recorded in the config hash,
    so rows made with other tools never mix. A name registered twice is an error naming both.
    """


# -- contribution hooks: dataset generation ---------------------------------------------------
@hookspec
def register_judges(register: Register) -> None:
    """Contribute surface judges: stage 3 of the paper's pipeline, for ``povagent generate``.

    Called once per plugin, when the plugin host first collects registered names (like the
    other ``register_*`` hooks; ``povagent generate``, a pipeline with ``dataset: {generate:
    ...}`` and ``povagent plugins`` all do). For each judge call
    ``register(name, factory, description="...")``. ``factory(**options)`` returns a
    :class:`povagent.generate.judge.SurfaceJudge`: any object with a method
    ``judge(request: JudgeRequest) -> SurfaceVerdict``. ``options`` are the
    ``--judge-option KEY=VALUE`` pairs of ``povagent generate`` or the pipeline YAML's
    ``dataset.generate.judge.options``; a factory that rejects them raises ``TypeError`` or
    ``ValueError``. The built-in ``physical-rules`` judge is the default.

    What a judge decides: for one (observer, anchor) pair and one direction (``right``,
    ``left``, ``front``, ``up``), whether a small target object (a book, a mug, boots) can
    physically stand there, ``SurfaceVerdict.verdict`` ``"appropriate"`` or
    ``"inappropriate"``, and on what, ``SurfaceVerdict.surface`` (``"on the floor"``,
    ``"on the bed"``): the surface picks the target pool and the ground-truth height. The
    request carries the house model, both objects, the observer camera and the observer view's
    RGB image (``request.image``, 512 x 512 x 3), so a rules judge reads geometry and a VLM
    judge looks at the picture. The generator then checks the ground-truth point against walls
    and the house boundary, and keeps a pair only if at least two of its directions survive.

    The same request must get the same verdict (a VLM judge: temperature 0 and a response
    cache), or one seed no longer gives one dataset. With ``--jobs`` > 1 every worker process
    loads the plugins again and calls the factory itself, so a judge need not pickle; the
    factory, not the module, should import heavy libraries, since every povagent command loads
    every plugin module.
    """


# -- lifecycle hooks ---------------------------------------------------------------------------
@hookspec
def povagent_run_start(run_dir: str, config: Mapping[str, Any], n_pending: int, n_total: int) -> None:
    """A pipeline run starts: its folder is locked and resume has been planned, no request made.

    ``run_dir`` is the run folder, ``config`` the resolved pipeline (as a dict: defaults and
    the model profile filled in), ``n_total`` the number of (instance, run) keys and
    ``n_pending`` those still to do after resume. Each cell of a sweep is a run of its own.
    """


@hookspec
def povagent_instance_done(run_dir: str, row: ResultRow) -> None:
    """One (instance, run) key finished and its row was written (fsynced) to ``results.jsonl``.

    ``row`` is the :class:`~povagent.results.rows.ResultRow` as written: ``status``
    (``answered``, ``parse_error`` or ``infra_error``), the exchanges with the raw answers, the
    ``parse``, the ``scores`` and the usage. Called on the run's event loop: return quickly
    (hand slow work to a thread), since requests wait while it runs.
    """


@hookspec
def povagent_run_end(run_dir: str, summary: Mapping[str, Any]) -> None:
    """A pipeline run ended: finished, stopped early (fail fast, circuit breaker) or interrupted.

    ``summary`` is what ``summary.json`` holds (written just before): the breakdowns, the row
    counts by status, the usage, and ``complete``.
    """
