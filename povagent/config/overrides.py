"""How overrides merge into a pipeline document: nested mappings merged, plugin choices replaced whole.

Used where one pipeline is made from another: ``load_pipeline(..., overrides=...)`` and each
cell of a sweep (:mod:`povagent.run.sweep`). A plugin's options never leak into another
plugin's: the keys in :data:`REPLACED_WHOLE` are replaced, not merged.

Pure: this module works on plain mappings; it must not validate them or read files.
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

#: Top-level keys an override replaces whole: options of one plugin never leak into another's.
REPLACED_WHOLE = frozenset({"model", "backend", "strategy", "parser", "scorers"})


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any], replace: frozenset[str] = frozenset()) -> dict[str, Any]:
    """``base`` with ``override`` merged in (nested mappings merged, everything else replaced;
    keys in ``replace`` are replaced whole)."""
    out = copy.deepcopy(dict(base))
    for k, v in override.items():
        if k not in replace and isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out
