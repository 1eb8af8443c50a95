"""What tells a choice scorer's row scores apart, and the label a row's choice scorer recorded.

A choice scorer (:mod:`povagent_plugins.scorers.choice_scorer` and the scorers built on it) writes
:data:`CHOICE_FIELDS`; the report reads any scorer writing them as one, whatever its name. Pure
reading of a row's stored scores: nothing here scores or opens a file.
"""

from __future__ import annotations

import sys

from povagent.results.rows import ResultRow

#: The fields a choice scorer writes: a row's scores carrying them all are a choice scorer's.
CHOICE_FIELDS = frozenset({"answered", "correct", "chosen", "gold", "category"})


def chosen_label(row: ResultRow) -> str | None:
    """The label the row's first choice scorer (a scorer writing :data:`CHOICE_FIELDS`)
    recorded as chosen (``None``: none scored it, or the reply named no option)."""
    for fields in row.scores.values():
        if fields.keys() >= CHOICE_FIELDS:
            return None if fields["chosen"] is None else sys.intern(str(fields["chosen"]))
    return None
