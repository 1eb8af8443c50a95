"""The plugins a pipeline names: loaded, checked and resolved before any request.

:func:`checked_plugins` applies the plugin rule (:mod:`povagent.config.plugin_rule`) to the
``plugins:`` list; :func:`plugin_host_for` loads them; :func:`check_plugin_names` makes sure every
backend, strategy, parser, scorer, judge and model profile named is registered (an error names
the line and the nearest name), and that every ``*_env`` option names an environment variable
rather than holding a key; :func:`resolve_components` fills in what a ``model:`` profile implies.

This module must not validate the schema (:mod:`povagent.config.models`), read files, or run
anything: it only asks the plugin host what is registered.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from povagent.config.models import ComponentSpec, PipelineConfig
from povagent.config.plugin_rule import allowed_plugins
from povagent.config.profiles import near_profile
from povagent.config.quoting import Loc, cut, dotted
from povagent.config.remote_code import check_remote_code_options
from povagent.config.yaml_reader import ConfigSource
from povagent.dataset.formats import missing_rules, registered_format
from povagent.errors import ConfigError, PluginError
from povagent.plugins import PluginHost, get_plugin_host, unknown_name_message
from povagent.results.official_reading import OFFICIAL_PARSER
from povagent.run.logs import ENV_NAME_WANTED, Redactor


def check_plugin_names(config: PipelineConfig, host: PluginHost, source: ConfigSource, prefix: Loc = ()) -> None:
    """Every plugin name in ``config`` must be registered; errors name the line and a near name."""
    problems: list[str] = []

    def check(kind: str, name: str, loc: Loc) -> None:
        known = host.names(kind)
        if name not in known:
            problems.append(f"{source.where(prefix + loc)}: {dotted(loc)}: {unknown_name_message(kind, cut(name), known)}")

    if config.model is not None:
        check("profile", config.model, ("model",))
    if config.backend is not None:
        check("backend", config.backend.name, ("backend", "name") if ("backend", "name") in source.lines else ("backend",))
        check_profile_option(config.backend, host, source, prefix, problems)
        check_env_options(config.backend.options, ("backend", "options"), source, prefix, problems)
        check_remote_code_options(config.backend.options, ("backend", "options"), source, prefix, problems)
    check("strategy", config.strategy.name, ("strategy", "name") if ("strategy", "name") in source.lines else ("strategy",))
    if config.parser is not None:
        check("parser", config.parser.name, ("parser", "name") if ("parser", "name") in source.lines else ("parser",))
    for i, scorer in enumerate(config.scorers):
        check("scorer", scorer.name, ("scorers", i))
    if config.dataset.format is not None:
        check("format", config.dataset.format, ("dataset", "format"))
        if config.dataset.format in host.names("format"):
            check_format_fits(config, host, source, prefix, problems)
    if config.dataset.generate is not None:
        loc = ("dataset", "generate", "judge")
        check("judge", config.dataset.generate.judge.name, loc + ("name",) if loc + ("name",) in source.lines else loc)
    for loc, options in component_options(config):
        check_finite_options(options, loc, source, prefix, problems)
    if problems:
        raise ConfigError("invalid pipeline:\n" + "\n".join(problems))


def check_format_fits(config: PipelineConfig, host: PluginHost, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """The registered format ``dataset.format`` names has its official rule (a registered parser
    and scorer: :func:`~povagent.dataset.formats.missing_rules`), and takes every key of ``dataset.options``."""
    fmt = str(config.dataset.format)
    at: Loc = ("dataset", "format")
    problems += [f"{source.where(prefix + at)}: {dotted(at)}: {why}" for why in missing_rules(host, [fmt])]
    accepted = registered_format(host, fmt).option_names
    for key in config.dataset.options or {}:
        if key not in accepted:
            loc: Loc = ("dataset", "options", key)
            takes = f"it takes {', '.join(accepted)}" if accepted else "it takes none"
            problems.append(f"{source.where(prefix + loc)}: {dotted(loc)}: format {fmt!r} has no option {cut(str(key))!r}; {takes}")


def check_env_options(options: Any, loc: Loc, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """Every ``*_env`` option (``api_key_env``, also inside router deployments) must name an
    environment variable; a key pasted there is refused at its line and never repeated."""
    redactor = Redactor()
    stack: list[tuple[Loc, Any]] = [(loc, options)]
    while stack:
        here, value = stack.pop()
        if isinstance(value, Mapping):
            for k, v in value.items():
                if isinstance(k, str) and k.lower().endswith("_env") and v is not None:
                    if not (isinstance(v, str) and redactor.plausible_variable_name(v)):
                        problems.append(f"{source.where(prefix + here + (k,))}: {dotted(here + (k,))}: {ENV_NAME_WANTED}")
                else:
                    stack.append((here + (k,), v))
        elif isinstance(value, list):
            stack.extend((here + (i,), v) for i, v in enumerate(value))


def component_options(config: PipelineConfig) -> list[tuple[Loc, Any]]:
    """Each named component's ``options`` with where they are in the pipeline."""
    found: list[tuple[Loc, Any]] = [(("strategy", "options"), config.strategy.options)]
    if config.backend is not None:
        found.append((("backend", "options"), config.backend.options))
    if config.parser is not None:
        found.append((("parser", "options"), config.parser.options))
    found += [(("scorers", i, "options"), s.options) for i, s in enumerate(config.scorers)]
    if config.dataset.generate is not None:
        found.append((("dataset", "generate", "judge", "options"), config.dataset.generate.judge.options))
    return found


def check_finite_options(options: Any, loc: Loc, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """Every number among a component's options is finite: ``.nan`` or ``.inf`` (YAML's spellings)
    as a temperature or a limit is refused at its line, not met by every request in turn."""
    stack: list[tuple[Loc, Any]] = [(loc, options)]
    while stack:
        here, value = stack.pop()
        if isinstance(value, float) and not math.isfinite(value):
            problems.append(f"{source.where(prefix + here)}: {dotted(here)}: {value} is not a finite number; give a number")
        elif isinstance(value, Mapping):
            stack.extend((here + (k,), v) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((here + (i,), v) for i, v in enumerate(value))


def check_profile_option(backend: ComponentSpec, host: PluginHost, source: ConfigSource, prefix: Loc, problems: list[str]) -> None:
    """A near miss of a model profile as the litellm backend's ``model`` option gets the same
    "did you mean" as under ``model:`` (a bare name far from every profile is a litellm model)."""
    model = backend.options.get("model")
    if backend.name != "litellm" or not isinstance(model, str):
        return
    known = host.names("profile")
    if near_profile(model, known) is not None:
        loc = ("backend", "options", "model")
        problems.append(f"{source.where(prefix + loc)}: {dotted(loc)}: {unknown_name_message('profile', cut(model), known)}")


#: Backends whose ``model`` option may name a model profile (which then brings its defaults).
PROFILE_BACKENDS = frozenset({"litellm", "transformers"})


def resolve_components(config: PipelineConfig, host: PluginHost) -> PipelineConfig:
    """Fill in what a ``model:`` profile implies: the backend (litellm with that model) and,
    when no parser is given, the parser the strategy's answers need (its ``answer_parser``),
    else, for a choice strategy on an external set, that set's official rule
    (:func:`set_official_parser`), else the strategy's default, else the profile's default parser (``official`` otherwise: a repair
    parser runs only when a pipeline or a profile names it). A profile named
    as the litellm backend's ``model`` option (how a vLLM profile gets its ``api_base``) brings
    its parser and strategy defaults the same way, and so does one named as the in-process
    ``transformers`` backend's ``model`` (a profile with a ``checkpoint``)."""
    config = set_defaults(config, host)
    backend, parser, strategy = config.backend, config.parser, config.strategy
    if parser is None:  # a strategy whose answers one parser reads gets it, whatever a profile says
        needed = needed_parser(host, strategy.name) or set_official_parser(config, host) or strategy_default_parser(host, strategy.name)
        parser = ComponentSpec(name=needed) if needed is not None else None
    profile = None
    if config.model is not None:
        profile = host.profile(config.model)
        # The litellm backend resolves a profile name given as its model (and applies the
        # profile's backend options itself).
        backend = ComponentSpec(name=getattr(profile, "backend", None) or "litellm", options={"model": config.model})
    elif backend is not None and backend.name in PROFILE_BACKENDS and backend.options.get("model") in host.names("profile"):
        profile = host.profile(backend.options["model"])
    if profile is not None:
        if parser is None:
            default = getattr(profile, "default_parser", None) or getattr(profile, "parser", None)
            if isinstance(default, str):
                parser = ComponentSpec(name=default)
        defaults = getattr(profile, "strategy_options", None)
        if isinstance(defaults, Mapping) and defaults:
            strategy = strategy.model_copy(update={"options": {**defaults, **strategy.options}})
    if parser is None:
        parser = ComponentSpec(name=OFFICIAL_PARSER)
    return config.model_copy(update={"backend": backend, "parser": parser, "strategy": strategy})


def set_defaults(config: PipelineConfig, host: PluginHost) -> PipelineConfig:
    """``config`` with the strategy and scorers a named dataset format chooses where the pipeline
    names none (``dataset: {format: mindcube}`` and a model is a complete pipeline): its answer
    type's ``default_strategy`` and ``default_scorers``, the format's official scorer first
    (:attr:`~povagent.dataset.formats.DatasetFormat.official_scorer`); a name the pipeline gives
    is kept, and a set with no ``dataset.format`` keeps the pipeline's defaults."""
    fmt = config.dataset.format
    if fmt is None or fmt not in host.names("format"):
        return config
    dataset_format = registered_format(host, fmt)
    if dataset_format.answer_type not in host.names("answer_type"):
        return config
    answer_type = host.answer_type(dataset_format.answer_type)
    update: dict[str, Any] = {}
    if "strategy" not in config.model_fields_set and answer_type.default_strategy is not None:
        update["strategy"] = ComponentSpec(name=answer_type.default_strategy)
    if "scorers" not in config.model_fields_set:
        names = [dataset_format.official_scorer, *answer_type.default_scorers]
        update["scorers"] = [ComponentSpec(name=n) for n in dict.fromkeys(names)]
    return config.model_copy(update=update) if update else config


def needed_parser(host: PluginHost, strategy: str) -> str | None:
    """The parser strategy ``strategy``'s answers need (its ``answer_parser``), or ``None``."""
    needed = getattr(host.entry("strategy", strategy).factory, "answer_parser", None)
    return needed if isinstance(needed, str) else None


def set_official_parser(config: PipelineConfig, host: PluginHost) -> str | None:
    """The official rule of the dataset format a pipeline names (``dataset.format``): what it gets
    when it names no parser, before the strategy's generic default, when the strategy asks the
    format's answer type; ``None`` for a set with no ``dataset.format``, a strategy asking for
    another answer type, or a format whose rule is the generic ``official`` (which a model
    profile's parser may still replace, as on any POVBench-layout set)."""
    fmt = config.dataset.format
    if fmt is None or fmt not in host.names("format"):
        return None
    dataset_format = registered_format(host, fmt)
    asked = getattr(host.entry("strategy", config.strategy.name).factory, "answer_type", "point")
    if asked != dataset_format.answer_type or dataset_format.official_parser == OFFICIAL_PARSER:
        return None
    return dataset_format.official_parser


def strategy_default_parser(host: PluginHost, strategy: str) -> str | None:
    """The parser strategy ``strategy`` gives a pipeline that names none (its ``default_parser``), or ``None``."""
    default = getattr(host.entry("strategy", strategy).factory, "default_parser", None)
    return default if isinstance(default, str) else None


def parser_misfit(host: PluginHost, strategy: str, parser: str) -> str | None:
    """Why parser ``parser`` cannot read strategy ``strategy``'s answers, or ``None`` when it can:
    the strategy needs another parser, or asks for an answer type the parser does not read."""
    needed = needed_parser(host, strategy)
    if needed is not None and parser != needed:
        return f"parser {parser!r} cannot read the answers of strategy {strategy!r}, which need parser {needed!r} (name it, or leave parser: out)"
    asked = getattr(host.entry("strategy", strategy).factory, "answer_type", "point")
    if asked not in host.names("answer_type"):
        known = ", ".join(host.names("answer_type")) or "none"
        return f"strategy {strategy!r} asks for a {asked} answer, an answer type no loaded plugin registers (registered: {known})"
    reads = getattr(host.entry("parser", parser).factory, "answer_types", frozenset({"point"}))
    if asked not in reads:
        return f"parser {parser!r} reads {', '.join(sorted(reads))} answers, and strategy {strategy!r} asks for a {asked} answer"
    return None


def check_parser_fits(config: PipelineConfig, host: PluginHost, source: ConfigSource, prefix: Loc = ()) -> None:
    """The resolved parser must read what the strategy asks: one line naming the ``parser:`` line
    (the strategy's when the parser came from a default), before any request."""
    assert config.parser is not None, "resolve_components() first"
    misfit = parser_misfit(host, config.strategy.name, config.parser.name)
    if misfit is not None:
        loc = ("parser",) if prefix + ("parser",) in source.lines else ("strategy",)
        raise ConfigError(f"{source.where(prefix + loc)}: {misfit}")


def check_task_fits(config: PipelineConfig, host: PluginHost, source: ConfigSource, prefix: Loc = ()) -> None:
    """A pipeline's ``task:`` other than the point task is answered as its ``answer``: the
    strategy must ask for that answer type (one line naming the ``strategy:`` line)."""
    if config.task.is_point_task:
        return
    factory = host.entry("strategy", config.strategy.name).factory
    if config.task.answer == "walk":  # a walk is the active mode's: a strategy of that task walks it
        if getattr(factory, "task", None) != config.task.name:
            raise ConfigError(
                f"{source.where(prefix + ('strategy',))}: task {config.task.name} is walked in active mode, and strategy "
                f"{config.strategy.name!r} does not walk it: name strategy: navigate (or leave strategy: out)"
            )
        return
    asked = getattr(factory, "answer_type", "point")
    if asked != config.task.answer:
        raise ConfigError(
            f"{source.where(prefix + ('strategy',))}: task {config.task.name} is answered as a {config.task.answer}, "
            f"and strategy {config.strategy.name!r} asks for a {asked} answer: name a strategy that asks for a {config.task.answer}"
        )


def plugin_host_for(plugins: list[str], source: ConfigSource, host: PluginHost | None) -> PluginHost:
    """The plugin host with the config's ``plugins`` loaded (into ``host`` when one is given);
    a plugin that fails to load is a :class:`ConfigError` at the ``plugins:`` line."""
    try:
        h = get_plugin_host(plugins) if host is None else host
        if host is not None:
            for mod in plugins:  # an explicit host still gets the config's modules
                if not h.pm.has_plugin(mod):
                    from povagent.plugins import _import_module_or_file

                    h.add_plugin(_import_module_or_file(mod), name=mod, source=f"config plugin {mod}")
        return h
    except PluginError as exc:
        raise ConfigError(f"{source.where(('plugins',))}: {exc}") from None
    except Exception as exc:
        raise ConfigError(f"{source.where(('plugins',))}: plugin failed to load: {type(exc).__name__}: {exc}") from None


def checked_plugins(plugins: list[str], source: ConfigSource, prefix: Loc = ()) -> list[str]:
    """``plugins`` as the rule of :mod:`povagent.config.plugin_rule` allows them: ``.py`` paths
    resolved inside the YAML file's folder (not the working directory, so the same file loads
    the same plugin wherever the command runs, as a pipeline or as a sweep's base), dotted names
    only from installed packages. A refused entry is a one-line :class:`ConfigError`; nothing is
    imported here. A mapping given from Python (``<pipeline mapping>``) is the caller's own code
    and keeps its entries as they are."""
    folder = source.plugin_folder()
    if folder is None or not plugins:
        return plugins
    return allowed_plugins(plugins, folder, [source.where(prefix + ("plugins", i)) for i in range(len(plugins))])
