"""The povagent plugin contract: every hook a plugin may implement.

Two kinds of hooks:

* **Contribution hooks** ``register_<things>(register)``: called once when plugins load. The
  plugin calls ``register(name, factory, description=...)`` for each thing it contributes; the
  core owns the names, so a name registered twice is an error that names both plugins. The
  return value is ignored.
* **Lifecycle hooks** ``povagent_*``: called by the runner as a run progresses, for loggers and
  live dashboards. They observe; their return value is ignored and they must not raise (an
  exception in one is logged and the run goes on).

Implement them with ``@povagent.hookimpl``. No hook here is ``firstresult``: none chooses
one answer among plugins.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Mapping

import pluggy

if TYPE_CHECKING:
    from povagent.results import ResultRow

PROJECT = "povagent"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)

#: ``register(name, factory, *, description="")``: the callback contribution hooks receive.
Register = Callable[..., None]


# -- contribution hooks ------------------------------------------------------------------------
@hookspec
def register_backends(register: Register) -> None:
    """Contribute model backends.

    Called once at plugin load. For each backend call
    ``register(name, factory, description="...")`` where ``factory(**options)`` returns a
    :class:`povagent.interfaces.Backend`; ``options`` are the pipeline YAML's ``backend.options``.
    """


@hookspec
def register_strategies(register: Register) -> None:
    """Contribute prompt strategies.

    Called once at plugin load; ``factory(**options)`` returns a
    :class:`povagent.interfaces.Strategy`.
    """


@hookspec
def register_parsers(register: Register) -> None:
    """Contribute output parsers.

    Called once at plugin load; ``factory(**options)`` returns a
    :class:`povagent.interfaces.Parser`.
    """


@hookspec
def register_scorers(register: Register) -> None:
    """Contribute scorers.

    Called once at plugin load; ``factory(**options)`` returns a
    :class:`povagent.interfaces.Scorer`.
    """


@hookspec
def register_model_profiles(register: Register) -> None:
    """Contribute model profiles: short names for models with their defaults.

    Called once at plugin load; ``register(name, profile)`` where ``profile`` is a
    :class:`povagent.profiles.ModelProfile` (litellm model string, default parser, quirks).
    """


# -- lifecycle hooks ---------------------------------------------------------------------------
@hookspec
def povagent_run_start(run_dir: str, config: Mapping[str, Any], n_pending: int, n_total: int) -> None:
    """A run starts.

    ``run_dir`` is the run folder, ``config`` the resolved pipeline (as a dict), ``n_total`` the
    number of (instance, run) keys and ``n_pending`` those still to do after resume.
    """


@hookspec
def povagent_instance_done(run_dir: str, row: "ResultRow") -> None:
    """One (instance, run) finished and its row was written (fsynced) to ``results.jsonl``."""


@hookspec
def povagent_run_end(run_dir: str, summary: Mapping[str, Any]) -> None:
    """A run ended (also after an interruption); ``summary`` is what ``summary.json`` holds."""
