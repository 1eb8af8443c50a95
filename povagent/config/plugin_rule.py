"""Which plugin code a config may load: the one rule that keeps "configs are untrusted" true.

A plugin is code and runs with the user's rights, so a YAML file (a pipeline, a sweep, a run
folder's ``config.yaml``) may not name just any code. The rule:

* a ``.py`` path under ``plugins:`` is read from the YAML file's own folder or below it. The
  path is resolved (``..`` and symlinks followed) before anything is read: an absolute path or a
  ``../`` outside that folder, or a symlink leading out of it, is refused;
* a dotted name is imported only from an installed package: it is looked up on ``sys.path``
  without the current directory (``''``, ``.`` or the working directory itself, which
  ``python -m`` puts first), so a ``.py`` lying in the working directory can never answer to it;
* a run folder's ``config.yaml`` loads nothing at all: ``rescore`` and ``report`` import only
  the modules their ``--plugin`` option names (:func:`missing_plugin_message` says which to
  pass).

The command line and installed (entry-point) plugins are trusted; nothing here applies to
them. A refused plugin is a :class:`~povagent.errors.ConfigError` of one line naming the file,
the line and the entry, raised before any plugin is imported.

This module only decides; it imports nothing it checks (see :mod:`povagent.plugins`).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import sys
from pathlib import Path
from typing import Sequence

from povagent.errors import ConfigError

#: What the rule says, quoted in every refusal so the way out is in the message.
RULE = "a config loads .py plugins only from its own folder or below, dotted names only from installed packages (docs/explanation/security.md)"


def is_plugin_path(entry: str) -> bool:
    """Whether a ``plugins:`` entry names a file (``x.py``, ``dir/x.py``) rather than a module."""
    return entry.endswith(".py") or "/" in entry or "\\" in entry


def allowed_plugins(plugins: Sequence[str], folder: Path, where: Sequence[str]) -> list[str]:
    """``plugins`` with every ``.py`` entry resolved to its absolute path, after checking the rule.

    ``folder`` is the folder of the YAML file that names them; ``where[i]`` says where entry
    ``i`` is written (``file, line N``) for messages. Raises :class:`ConfigError` (one line) on
    the first entry the rule refuses; imports nothing.
    """
    allowed = folder.resolve()
    out: list[str] = []
    for entry, place in zip(plugins, where):
        if not isinstance(entry, str) or not entry:
            raise ConfigError(f"{place}: plugins: each entry is a dotted module name or a .py path, got {entry!r}")
        out.append(_allowed_file(entry, allowed, place) if is_plugin_path(entry) else _allowed_module(entry, place))
    return out


def _allowed_file(entry: str, allowed: Path, place: str) -> str:
    written = Path(entry)
    if written.is_absolute() or entry.startswith("~"):
        candidate = Path(os.path.expanduser(entry))
    else:
        candidate = allowed / written
    resolved = candidate.resolve()  # symlinks followed: a link leading out is judged by its target
    if not resolved.is_relative_to(allowed):
        # written inside the folder yet resolving outside it: a symlink leads out
        lexical = Path(os.path.normpath(candidate.absolute()))
        how = "a symlink leading" if lexical.is_relative_to(allowed) else "a path"
        shown = f" (to {resolved})" if how.startswith("a symlink") else ""
        raise ConfigError(
            f"{place}: plugin {entry!r} is {how} outside the config's folder{shown}: refused ({RULE}); "
            f"copy it into that folder or install it as a package"
        )
    if not resolved.is_file():
        raise ConfigError(f"{place}: plugin {entry!r}: no such file {resolved}")
    return str(resolved)


def _allowed_module(entry: str, place: str) -> str:
    if not all(part.isidentifier() for part in entry.split(".")):
        raise ConfigError(f"{place}: plugin {entry!r} is neither a dotted module name nor a .py path")
    top = entry.split(".", 1)[0]
    if top in sys.modules:  # already imported (povagent itself, a built-in): runs nothing new
        return entry
    installed = _find(top, installed_search_path())
    if installed is None:
        here = _find(top, sys.path + [os.getcwd()])
        if here is not None:
            raise ConfigError(
                f"{place}: plugin {entry!r} is not an installed package: it would be read from "
                f"{_origin(here)} in the working directory: refused ({RULE}); install it, or name its .py file "
                f"from the config's folder"
            )
        raise ConfigError(f"{place}: plugin {entry!r}: no installed module of that name (is it installed in this environment?)")
    actual = _find(top, sys.path)
    if actual is not None and _origin(actual) != _origin(installed):
        raise ConfigError(
            f"{place}: plugin {entry!r} would be read from {_origin(actual)} in the working directory, not from "
            f"the installed {_origin(installed)}: refused ({RULE}); run from another folder"
        )
    return entry


def installed_search_path() -> list[str]:
    """``sys.path`` without the current directory: ``''``, ``.`` and the working directory."""
    cwd = os.path.realpath(os.getcwd())
    return [p for p in sys.path if p not in ("", ".") and os.path.realpath(p) != cwd]


def _find(name: str, path: list[str]) -> importlib.machinery.ModuleSpec | None:
    """Find a top-level module as ``import`` would, with ``path`` in place of ``sys.path``;
    executes nothing (meta-path finders such as editable installs are asked as usual)."""
    for finder in sys.meta_path:
        if finder is importlib.machinery.PathFinder:
            spec = importlib.machinery.PathFinder.find_spec(name, path)
        else:
            find_spec = getattr(finder, "find_spec", None)
            if find_spec is None:
                continue
            try:
                spec = find_spec(name, None)
            except Exception:
                spec = None
        if spec is not None:
            return spec
    return None


def _origin(spec: importlib.machinery.ModuleSpec) -> str:
    if spec.origin and spec.origin not in ("built-in", "frozen", "namespace"):
        return spec.origin
    locations = list(spec.submodule_search_locations or [])
    return locations[0] if locations else (spec.origin or spec.name)


def missing_plugin_message(command: str, run_dir: Path, kind: str, name: str, plugins: Sequence[str]) -> str:
    """One line: a run needs ``kind`` ``name``, which came from a plugin its config names, and
    ``command`` does not import code a run folder names: how to pass it on the command line."""
    if plugins:
        given = " ".join(f"--plugin {p}" for p in plugins)
        return (
            f"{run_dir / 'config.yaml'}: the run's {kind} {name!r} comes from a plugin its config names "
            f"({', '.join(plugins)}); povagent {command} never imports code a run folder names: check that "
            f"code, then pass it on the command line: povagent {command} {run_dir} {given}"
        )
    return f"{run_dir / 'config.yaml'}: the run's {kind} {name!r} is not registered; pass the plugin that defines it with --plugin MODULE_OR_FILE"
