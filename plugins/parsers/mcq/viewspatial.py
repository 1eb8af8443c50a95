"""The ``viewspatial`` parser: ViewSpatial-Bench's official rule, as lmms-eval's ``viewspatial`` task runs it.

The rule (``extract_option`` and ``viewspatial_process_results`` of lmms-eval's
``lmms_eval/tasks/viewspatial/utils.py``, the same ``extract_option`` as the set's own
``evaluate.py``): after lmms-eval's reasoning strip, only the last line of the reply counts
(text after the last newline, so a reply ending in a newline has an empty last line in the
set's own script, but lmms-eval has stripped it); the first ``A``-``D`` standing alone as a
word, in either case, upper-cased, is the label. ``b`` is ``B``; "A chair..." on the last line
is ``A``. The gold ``"A. right"`` reads as ``A`` by the same rule.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, VIEWSPATIAL_BENCH

_WORD_LETTER = re.compile(r"\b([A-D])\b", re.IGNORECASE)


def viewspatial_label(text: str) -> str | None:
    """The label ViewSpatial-Bench's rule reads in ``text`` (module docstring), or ``None``."""
    last_line = strip_reasoning_blocks(text).split("\n")[-1]
    found = _WORD_LETTER.search(last_line)
    return found.group(1).upper() if found else None


class ViewSpatialParser(RuleParser):
    """ViewSpatial-Bench's rule (module docstring)."""

    reads = "the first A-D standing alone on the last line, any case (ViewSpatial-Bench's official rule, lmms-eval's viewspatial)"
    beside_official = "reads choice answers, which the official (point) parser does not read; ViewSpatial-Bench's own rule"

    def label(self, text: str, spec: AnswerSpec) -> str | None:
        """The rule's label."""
        return viewspatial_label(text)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the viewspatial parser."""
    register("viewspatial", ViewSpatialParser, description=(
        f"ViewSpatial-Bench's official rule: the first A-D word on the last line (lmms-eval "
        f"lmms_eval/tasks/viewspatial/utils.py extract_option @ {LMMS_EVAL}; = {VIEWSPATIAL_BENCH} evaluate.py)"))  # fmt: skip
