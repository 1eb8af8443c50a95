"""The plugin host: loads plugins, owns the names they register, and calls lifecycle hooks.

Plugins come from three places, loaded the same way (pluggy's public API only):

1. the built-ins listed in :data:`povagent.default_plugins.DEFAULT_PLUGINS`;
2. the entry-point group ``povagent`` of installed distributions;
3. modules named under ``plugins:`` in a pipeline YAML (a dotted module name, or a path to a
   ``.py`` file), once :mod:`povagent.config.plugin_rule` has allowed them (a ``.py`` from the
   YAML's own folder, a dotted name from an installed package), and modules named by
   ``--plugin`` on the command line.

Contribution hooks (``register_backends`` ...) are called once per plugin with a ``register``
callback the host owns, so every name resolves to exactly one plugin and a duplicate is a
:class:`~povagent.errors.PluginError` naming both. A plugin that fails to import is reported by
name with its error. Lifecycle hooks go through :class:`LifecycleHooks`, a typed facade that
never lets an observer's exception end a run.

This module must not import any plugin by name except through ``DEFAULT_PLUGINS``.
"""

from __future__ import annotations

import difflib
import importlib
import importlib.metadata
import importlib.util
import re
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Callable, Iterable, Literal, Mapping, Sequence

import pluggy
import structlog

from povagent import hookspecs
from povagent.answers.types import AnswerType
from povagent.errors import PluginError
from povagent.interfaces import Backend, Parser, Scorer, Strategy

if TYPE_CHECKING:  # the active mode loads with the first episode, not with the plugin list
    from povagent.active.tools import ToolSet

#: The kinds of things plugins contribute through a factory, and the hook for each.
Kind = Literal["backend", "strategy", "parser", "scorer", "judge"]
KIND_HOOKS: dict[str, str] = {
    "backend": "register_backends",
    "strategy": "register_strategies",
    "parser": "register_parsers",
    "scorer": "register_scorers",
    "judge": "register_judges",
}
KINDS: tuple[str, ...] = tuple(KIND_HOOKS)
PROFILE_HOOK = "register_model_profiles"
#: Contribution hooks that register objects rather than factories, and the kind each fills.
OBJECT_HOOKS: dict[str, str] = {"profile": PROFILE_HOOK, "answer_type": "register_answer_types", "format": "register_dataset_formats"}

#: The hook active-mode tools are registered by (kept in load order: the order they are offered).
TOOL_HOOK = "register_tools"
_TOOL_NAME = re.compile(r"[A-Za-z0-9_-]{1,64}")

#: The entry-point group third-party distributions declare their plugins under.
ENTRY_POINT_GROUP = "povagent"


@dataclass(frozen=True)
class PluginEntry:
    """One registered thing: its kind, name, factory (or profile object) and where it came from."""

    kind: str
    name: str
    factory: Any
    description: str
    source: str


@dataclass(frozen=True)
class LoadFailure:
    """A plugin that could not be loaded, by name, with its error."""

    plugin: str
    origin: str
    error: str
    traceback: str

    def __str__(self) -> str:
        return f"plugin {self.plugin!r} ({self.origin}) failed to load: {self.error}"


def did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest candidate, or ``""`` when none is close."""
    close = difflib.get_close_matches(name, list(candidates), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


class LifecycleHooks:
    """Typed facade over the lifecycle hooks: the runner calls these, never ``pm.hook.*``.

    Each implementation is called on its own so that one observer raising neither stops the
    run nor silences the other observers; the error goes to ``on_error``.
    """

    def __init__(self, pm: pluggy.PluginManager, on_error: Callable[[str, str, BaseException], None] | None = None) -> None:
        self._pm = pm
        self.on_error = on_error or _log_hook_error

    def _call(self, hook_name: str, kwargs: dict[str, Any]) -> None:
        caller = getattr(self._pm.hook, hook_name)
        # pluggy calls the last registered first; keep that order.
        for impl in reversed(caller.get_hookimpls()):
            try:
                impl.function(**{a: kwargs[a] for a in impl.argnames})
            except Exception as exc:  # an observer must never end a run
                self.on_error(hook_name, impl.plugin_name, exc)

    @property
    def active(self) -> bool:
        """True when any plugin observes the run (lets the runner skip building arguments)."""
        return any(
            getattr(self._pm.hook, h).get_hookimpls()
            for h in ("povagent_run_start", "povagent_instance_done", "povagent_run_end")
        )

    def run_start(self, run_dir: str, config: Mapping[str, Any], n_pending: int, n_total: int) -> None:
        """Fire ``povagent_run_start``."""
        self._call("povagent_run_start", {"run_dir": run_dir, "config": config, "n_pending": n_pending, "n_total": n_total})

    def instance_done(self, run_dir: str, row: Any) -> None:
        """Fire ``povagent_instance_done`` (after the row is durable)."""
        if self._pm.hook.povagent_instance_done.get_hookimpls():
            self._call("povagent_instance_done", {"run_dir": run_dir, "row": row})

    def run_end(self, run_dir: str, summary: Mapping[str, Any]) -> None:
        """Fire ``povagent_run_end``."""
        self._call("povagent_run_end", {"run_dir": run_dir, "summary": summary})


def _log_hook_error(hook: str, plugin: str, exc: BaseException) -> None:
    """Report a plugin that raised in a lifecycle hook through structlog, on stderr (looked up
    now, not at import), so ``--json`` output on stdout stays clean. A run's own log records
    the failure too."""
    log = structlog.wrap_logger(
        structlog.PrintLogger(sys.stderr),
        processors=[structlog.processors.add_log_level, structlog.dev.ConsoleRenderer(colors=False)],
    )
    log.warning("plugin_hook_error", plugin=plugin, hook=hook, error=f"{type(exc).__name__}: {exc}")


class PluginHost:
    """The loaded plugins and everything they registered.

    Build one with :func:`get_plugin_host` (cached) or :func:`build_plugin_host` (fresh).
    ``strict=False`` keeps going past plugins that fail to load (``povagent plugins`` lists
    them); a strict host raises :class:`PluginError` instead.
    """

    def __init__(self, pm: pluggy.PluginManager, sources: dict[str, str], failures: list[LoadFailure]) -> None:
        self.pm = pm
        self._sources = sources  # pluggy plugin name -> human-readable origin
        self.failures = failures
        self.hooks = LifecycleHooks(pm)
        self._registry: dict[str, dict[str, PluginEntry]] | None = None
        self._tools: ToolSet | None = None

    # -- registration -------------------------------------------------------------------------
    def _collect(self) -> dict[str, dict[str, PluginEntry]]:
        if self._registry is not None:
            return self._registry
        registry: dict[str, dict[str, PluginEntry]] = {k: {} for k in (*KINDS, *OBJECT_HOOKS)}
        for kind, hook_name in (*KIND_HOOKS.items(), *OBJECT_HOOKS.items()):
            table = registry[kind]
            caller = getattr(self.pm.hook, hook_name)
            for impl in reversed(caller.get_hookimpls()):
                source = self.source_of(impl.plugin_name)

                def register(name: str, factory: Any, description: str = "", *, _kind=kind, _table=table, _source=source) -> None:
                    if not isinstance(name, str) or not name:
                        raise PluginError(f"{_source}: registered a {_kind} with an invalid name {name!r}")
                    known = _table.get(name)
                    if known is not None:
                        raise PluginError(
                            f"{_kind} name {name!r} is registered twice: by {known.source} and by {_source}; "
                            f"uninstall or rename one of them"
                        )
                    _table[name] = PluginEntry(_kind, name, factory, description or _first_line(factory), _source)

                try:
                    impl.function(**{a: register for a in impl.argnames})
                except PluginError:
                    raise
                except Exception as exc:
                    raise PluginError(f"{source}: {hook_name} raised {type(exc).__name__}: {exc}") from exc
        self._registry = registry
        return registry

    def source_of(self, plugin_name: str) -> str:
        """Where a pluggy plugin came from, e.g. ``built-in povagent_plugins.scorers.official_scorer``."""
        return self._sources.get(plugin_name, f"plugin {plugin_name}")

    def add_plugin(self, plugin: object, name: str | None = None, source: str | None = None) -> str:
        """Register a plugin object (a module or any object with hook implementations).

        Used for throwaway plugins in tests; names are collected again on next use.
        """
        try:
            registered = self.pm.register(plugin, name=name)
            self.pm.check_pending()
        except pluggy.PluginValidationError as exc:
            if name and self.pm.get_plugin(name) is plugin:
                self.pm.unregister(name=name)
            raise PluginError(f"plugin {name or plugin!r} is invalid: {exc}") from exc
        if registered is None:  # already registered: harmless
            registered = self.pm.get_name(plugin) or ""
        self._sources[registered] = source or f"plugin {registered}"
        self._registry = None
        self._tools = None
        return registered

    def remove_plugin(self, name: str) -> None:
        """Unregister a plugin added with :meth:`add_plugin`."""
        if self.pm.get_plugin(name) is not None:
            self.pm.unregister(name=name)
        self._sources.pop(name, None)
        self._registry = None
        self._tools = None

    def tools(self, task: str | None = "point") -> ToolSet:
        """The registered active-mode tools an episode of ``task`` offers (the point task's by
        default, as every episode offered before tasks; ``None``: every registered tool), in the
        order the plugins were loaded (the order an episode offers them); a name registered
        twice is a :class:`PluginError` naming both."""
        every = self._registered_tools()
        return every if task is None else every.for_task(task)

    def _registered_tools(self) -> ToolSet:
        if self._tools is not None:
            return self._tools
        from povagent.active.tools import Tool, ToolSet

        found: dict[str, tuple[Tool, str]] = {}
        for impl in self.pm.hook.register_tools.get_hookimpls():  # load order, unlike a hook call
            source = self.source_of(impl.plugin_name)

            def register(name: str, tool: Tool, *, _source: str = source) -> None:
                if not isinstance(name, str) or not _TOOL_NAME.fullmatch(name):  # what function calling accepts
                    raise PluginError(f"{_source}: registered a tool with an invalid name {name!r} (letters, digits, _ and -, at most 64)")
                if not isinstance(tool, Tool):
                    raise PluginError(f"{_source}: tool {name!r} is a {type(tool).__name__}, not a povagent.active.tools.Tool")
                if name in found:
                    raise PluginError(f"tool name {name!r} is registered twice: by {found[name][1]} and by {_source}; uninstall or rename one of them")
                found[name] = (tool, _source)

            try:
                impl.function(**{a: register for a in impl.argnames})
            except PluginError:
                raise
            except Exception as exc:
                raise PluginError(f"{source}: {TOOL_HOOK} raised {type(exc).__name__}: {exc}") from exc
        self._tools = ToolSet(((name, tool) for name, (tool, _) in found.items()), {n: s for n, (_, s) in found.items()})
        return self._tools

    def tool_entries(self) -> list[PluginEntry]:
        """Every registered tool as ``povagent plugins`` lists it, in the order offered."""
        tools = self.tools(None)
        return [PluginEntry("tool", n, t, t.description, tools.sources.get(n, "")) for n, t in tools.tools.items()]

    # -- lookup -------------------------------------------------------------------------------
    def names(self, kind: str) -> list[str]:
        """Sorted names registered for ``kind`` (``backend``, ``strategy``, ``parser``, ``scorer``,
        ``judge``, ``profile``)."""
        return sorted(self._table(kind))

    def entries(self, kind: str) -> list[PluginEntry]:
        """Every entry of ``kind``, sorted by name."""
        table = self._table(kind)
        return [table[n] for n in sorted(table)]

    def entry(self, kind: str, name: str) -> PluginEntry:
        """The entry for ``name``; unknown names raise :class:`PluginError` with a suggestion."""
        table = self._table(kind)
        found = table.get(name)
        if found is None:
            raise PluginError(unknown_name_message(kind, name, table))
        return found

    def create(self, kind: str, name: str, options: Mapping[str, Any] | None = None) -> Any:
        """Instantiate ``name`` of ``kind`` with its YAML options (``factory(**options)``)."""
        entry = self.entry(kind, name)
        try:
            return entry.factory(**dict(options or {}))
        except PluginError:
            raise
        except (TypeError, ValueError) as exc:
            # Wrong or invalid options: a user error worth a clear message, not a traceback.
            # The message reaches the terminal: a secret passed as an option must not.
            from povagent.files.redaction import Redactor

            redactor = Redactor()
            shown = redactor.value(dict(options or {}))
            raise PluginError(redactor.text(f"{kind} {name!r} ({entry.source}) rejected its options {shown!r}: {exc}")) from None

    # -- the typed seam: one method per kind, each returning what the interfaces promise ------
    def backend(self, name: str, options: Mapping[str, Any] | None = None) -> Backend:
        """The backend registered as ``name``, made with its YAML ``options``."""
        return self._made("backend", name, options, Backend)

    def strategy(self, name: str, options: Mapping[str, Any] | None = None) -> Strategy:
        """The strategy registered as ``name``, made with its YAML ``options``, and handed these
        plugins (:meth:`~povagent.interfaces.Strategy.use_plugins`: the tools it offers are this
        host's, wherever it is made: a run, ``show-prompt``, a dry run, ``rescore``)."""
        made = self._made("strategy", name, options, Strategy)
        made.use_plugins(self)
        return made

    def parser(self, name: str, options: Mapping[str, Any] | None = None) -> Parser:
        """The parser registered as ``name``, made with its YAML ``options``."""
        return self._made("parser", name, options, Parser)

    def scorer(self, name: str, options: Mapping[str, Any] | None = None) -> Scorer:
        """The scorer registered as ``name``, made with its YAML ``options``."""
        return self._made("scorer", name, options, Scorer)

    def _made(self, kind: str, name: str, options: Mapping[str, Any] | None, expected: type) -> Any:
        """What :meth:`create` makes, held to its kind's base class: a factory that returns
        something else is the plugin's bug, named when it is made rather than met as an
        AttributeError mid-run."""
        made = self.create(kind, name, options)
        if not isinstance(made, expected):
            raise PluginError(
                f"{kind} {name!r} ({self.entry(kind, name).source}) made a {type(made).__name__}, not a "
                f"{expected.__name__}: its factory must return a povagent.interfaces.{expected.__name__}"
            )
        return made

    def profile(self, name: str) -> Any:
        """The model profile registered as ``name`` (see ``register_model_profiles``)."""
        return self.entry("profile", name).factory

    def answer_type(self, name: str) -> AnswerType:
        """The answer type registered as ``name`` (see ``register_answer_types``)."""
        found = self.entry("answer_type", name).factory
        if not isinstance(found, AnswerType):
            raise PluginError(f"{self.entry('answer_type', name).source}: answer type {name!r} is not a povagent.answers.types.AnswerType")
        return found

    def profiles(self) -> dict[str, Any]:
        """Every model profile by name."""
        return {n: e.factory for n, e in sorted(self._table("profile").items())}

    def _table(self, kind: str) -> dict[str, PluginEntry]:
        registry = self._collect()
        if kind not in registry:
            raise ValueError(f"unknown plugin kind {kind!r}; expected one of {', '.join(registry)}")
        return registry[kind]


def unknown_name_message(kind: str, name: str, known: Iterable[str]) -> str:
    """``unknown strategy 'spatial_cot' (did you mean 'spatial-cot'?); known: ...``."""
    known = sorted(known)
    listing = ", ".join(known) if known else "none registered"
    return f"unknown {kind} {name!r}{did_you_mean(name, known)}; known {kind} names: {listing}"


def _first_line(obj: Any) -> str:
    doc = getattr(obj, "__doc__", None) or ""
    return doc.strip().splitlines()[0] if doc.strip() else ""


# -- loading ------------------------------------------------------------------------------------
def _import_module_or_file(spec: str) -> ModuleType:
    """Import a dotted module name, or a ``.py`` file path (relative to the working directory)."""
    if spec.endswith(".py") or "/" in spec or "\\" in spec:
        path = Path(spec).expanduser().resolve()
        if not path.is_file():
            raise FileNotFoundError(f"no such plugin file: {path}")
        mod_name = f"povagent_local_plugin_{path.stem}_{abs(hash(str(path))) & 0xFFFFFF:x}"
        if mod_name in sys.modules:
            return sys.modules[mod_name]
        module_spec = importlib.util.spec_from_file_location(mod_name, path)
        assert module_spec is not None and module_spec.loader is not None
        module = importlib.util.module_from_spec(module_spec)
        sys.modules[mod_name] = module
        try:
            module_spec.loader.exec_module(module)
        except BaseException:
            sys.modules.pop(mod_name, None)
            raise
        return module
    return importlib.import_module(spec)


def _failure(plugin: str, origin: str, exc: BaseException) -> LoadFailure:
    return LoadFailure(plugin, origin, f"{type(exc).__name__}: {exc}", "".join(traceback.format_exception(exc)))


def build_plugin_host(
    extra_modules: Sequence[str] = (),
    *,
    strict: bool = True,
    entry_points: bool = True,
    default_plugins: Sequence[str] | None = None,
) -> PluginHost:
    """A fresh host with the built-ins, the entry-point plugins and ``extra_modules`` loaded.

    A module that fails to import (or carries hook implementations with no spec) raises
    :class:`PluginError` naming it, unless ``strict=False``, which records it in
    ``host.failures`` and goes on.
    """
    from povagent.default_plugins import DEFAULT_PLUGINS

    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    sources: dict[str, str] = {}
    failures: list[LoadFailure] = []

    def register(name: str, module: object, source: str) -> None:
        if pm.has_plugin(name) or pm.is_registered(module):
            return  # loading twice is harmless
        try:
            pm.register(module, name=name)
        except (pluggy.PluginValidationError, ValueError) as exc:
            failures.append(_failure(name, source, exc))
            return
        sources[name] = source

    for mod in DEFAULT_PLUGINS if default_plugins is None else default_plugins:
        try:
            register(mod, _import_module_or_file(mod), f"built-in {mod}")
        except Exception as exc:
            failures.append(_failure(mod, "built-in", exc))

    if entry_points:
        for ep in sorted(importlib.metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
            dist = getattr(ep, "dist", None)
            dist_label = f"{dist.metadata['Name']} {dist.version}" if dist is not None else "unknown distribution"
            origin = f"entry point {ep.name} = {ep.value} from {dist_label}"
            try:
                obj = ep.load()
            except Exception as exc:
                failures.append(_failure(ep.name, origin, exc))
                continue
            register(f"entrypoint:{ep.name}", obj, origin)

    for mod in extra_modules:
        try:
            register(mod, _import_module_or_file(mod), f"config plugin {mod}")
        except Exception as exc:
            failures.append(_failure(mod, "listed under plugins: in the config", exc))

    # Hook implementations with no spec (a typo like register_backend) are caught here.
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        plugin_name = pm.get_name(exc.plugin) or str(exc.plugin)
        failures.append(_failure(plugin_name, sources.get(plugin_name, "plugin"), exc))
        pm.unregister(exc.plugin)

    if strict and failures:
        raise PluginError("\n".join(str(f) for f in failures))
    return PluginHost(pm, sources, failures)


_HOSTS: dict[tuple[str, ...], PluginHost] = {}
#: A host that replaces every cached one (set by the ``povagent_host`` test fixture).
_OVERRIDE: PluginHost | None = None


def get_plugin_host(extra_modules: Sequence[str] = ()) -> PluginHost:
    """The process-wide host for these extra modules (built once, then cached).

    Raises :class:`PluginError` if any plugin fails to load.
    """
    if _OVERRIDE is not None:
        for mod in extra_modules:
            if not _OVERRIDE.pm.has_plugin(mod):
                try:
                    _OVERRIDE.add_plugin(_import_module_or_file(mod), name=mod, source=f"config plugin {mod}")
                except PluginError:
                    raise
                except Exception as exc:
                    raise PluginError(str(_failure(mod, "listed under plugins: in the config", exc))) from exc
        return _OVERRIDE
    key = tuple(extra_modules)
    host = _HOSTS.get(key)
    if host is None:
        host = _HOSTS[key] = build_plugin_host(key)
    return host
