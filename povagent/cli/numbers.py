"""How the console prints a mean: three decimals, ``-`` when there is none (or it is NaN)."""

from __future__ import annotations

import math


def format_number(v: float | None, digits: int = 3) -> str:
    """A mean for a table: ``-`` when missing."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{v:.{digits}f}"
