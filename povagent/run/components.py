"""The plugins a run uses, made once from its configuration, and the names its rows and
messages give them.

Made through the plugin host's typed seam (:meth:`~povagent.plugins.PluginHost.backend` and the
others), so each one is the interface's type; the runner, the sweep's dry run and the solve
step of one key (:mod:`povagent.run.solve_key`) share them.
"""

from __future__ import annotations

from dataclasses import dataclass

from povagent.answers.types import AnswerType
from povagent.config.models import PipelineConfig
from povagent.interfaces import Backend, Parser, Scorer, Strategy
from povagent.plugins import PluginHost, get_plugin_host
from povagent.results.official_reading import official_counterpart


@dataclass
class Components:
    """The plugins a run uses, created once."""

    backend: Backend
    strategy: Strategy
    parser: Parser
    scorers: dict[str, Scorer]
    #: The parser giving the official reading kept beside a lenient ``parser``'s, and its name
    #: (``None`` when ``parser`` reads officially itself).
    official_parser: Parser | None = None
    official_parser_name: str | None = None
    #: The answer type the strategy asks for (its ``answer_type``, as registered).
    answer_type: AnswerType | None = None


@dataclass(frozen=True)
class ComponentNames:
    """The registered names of a run's backend, strategy and parser, as its rows, log and
    summary name them."""

    backend: str
    strategy: str
    parser: str


def create_components(config: PipelineConfig, host: PluginHost) -> Components:
    """Instantiate the backend, strategy, parser and scorers named in ``config``."""
    assert config.backend is not None and config.parser is not None, "resolve_components() first"
    parser = host.parser(config.parser.name, config.parser.options)
    counterpart = official_counterpart(parser)
    strategy = host.strategy(config.strategy.name, config.strategy.options)
    return Components(
        backend=host.backend(config.backend.name, config.backend.options),
        strategy=strategy,
        parser=parser,
        scorers={s.name: host.scorer(s.name, s.options) for s in config.scorers},
        official_parser=host.parser(counterpart) if counterpart else None,
        official_parser_name=counterpart,
        answer_type=host.answer_type(strategy.answer_type),
    )


def pipeline_hash(config: PipelineConfig, strategy: Strategy | None = None) -> str:
    """The config hash a run's rows carry: the YAML's, with what its strategy says decides its
    rows beyond it (:meth:`~povagent.interfaces.Strategy.identity`, e.g. the tools offered).
    ``strategy`` is the run's; without it, one is made with the config's plugins (dry runs)."""
    if strategy is None:
        strategy = get_plugin_host(config.plugins).strategy(config.strategy.name, config.strategy.options)
    return config.config_hash(strategy.identity())


def backend_label(backend: Backend) -> str:
    """``model at URL`` (or the backend's name) for messages about an unreachable backend."""
    try:
        ident = dict(backend.identity())
    except Exception:  # identity is for the cache; a message must not fail on it
        ident = {}
    model = ident.get("model") or ident.get("backend") or type(backend).__name__
    base = ident.get("api_base")
    return f"model {model} at {base}" if base else f"model {model}"


def answering_model(backend: Backend) -> tuple[str, str | None]:
    """``(model, profile)`` of a backend, as rows and ``summary.json`` name it: the model string
    its identity names (litellm: the string sent, e.g. ``openai/gpt-5.4``), else the backend's
    own name (``center``, ``replay``); the profile's name when it was named by one."""
    try:
        ident = dict(backend.identity())
    except Exception:  # identity is for the cache; naming the model must not fail on it
        ident = {}
    model = ident.get("model") or ident.get("backend") or type(backend).__name__
    profile = getattr(getattr(backend, "profile", None), "name", None)
    return str(model), profile if isinstance(profile, str) else None
