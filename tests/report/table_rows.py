"""Reading one system's row out of a report table, for tests that pick one number."""

from __future__ import annotations

from povagent.report.tables import Row, Table


def system_row(t: Table, system: str) -> Row:
    """The row of ``system`` in ``t``; a KeyError names a system the table lacks."""
    for r in t.rows:
        if r.label == system:
            return r
    raise KeyError(system)
