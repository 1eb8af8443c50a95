"""Deterministic JSON: the one way the generator writes a JSON file.

What it is for: the same value gives the same bytes on every machine and run: keys sorted,
floats rounded to ``FLOAT_DECIMALS`` (-0.0 made 0.0), numpy scalars made plain, one trailing
newline. A room of its own, apart from the release writer (:mod:`povagent.generate.writer`,
which renders and encodes images), so the house records and ``meta.json`` are written by
processes that never load the renderer. What it must not do: decide content.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

#: Decimals kept for every float in JSON (0.1 mm: far below a pixel at any distance used here).
FLOAT_DECIMALS = 4


def rounded(value: Any) -> Any:
    """``value`` with every float rounded to ``FLOAT_DECIMALS`` (and -0.0 made 0.0)."""
    if isinstance(value, float):
        r = round(value, FLOAT_DECIMALS)
        return 0.0 if r == 0 else r
    if isinstance(value, (np.floating,)):
        return rounded(float(value))
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, dict):
        return {str(k): rounded(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [rounded(v) for v in value]
    return value


def write_json(path: Path, value: Any) -> None:
    """Write deterministic JSON: sorted keys, rounded floats, one trailing newline."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rounded(value), sort_keys=True, indent=1, ensure_ascii=False) + "\n")
