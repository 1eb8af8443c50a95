"""The ``viewspatial`` parser: ViewSpatial-Bench's rule, as lmms-eval's ``viewspatial`` task runs it (after
lmms-eval's reasoning-tag strip; the set's own ``evaluate.py``, with no strip, is ``viewspatial-official``).

The rule (``extract_option`` and ``viewspatial_process_results`` of lmms-eval's
``lmms_eval/tasks/viewspatial/utils.py``, the same ``extract_option`` as the set's own
``evaluate.py``): after lmms-eval's reasoning strip, only the last line of the reply counts
(text after the last newline, so a reply ending in a newline has an empty last line in the
set's own script, but lmms-eval has stripped it); the first ``A``-``D`` standing alone as a
word, in either case, upper-cased, is the label. ``b`` is ``B``; "A chair..." on the last line
is ``A``. The gold ``"A. right"`` reads as ``A`` by the same rule.

``viewspatial-official`` is the set's own ``evaluate.py`` (at the repository's root at the pinned
commit): the same letter rule on ``reply.split("\n")[-1]`` with nothing stripped first, so
``"B\n"`` reads nothing and ``"<think>A</think>B"`` reads ``A``.
"""

from __future__ import annotations

import re

from povagent import hookimpl
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

    reads = ("lmms-eval's viewspatial: its reasoning-tag strip (<think>, <analysis> blocks, then whitespace), then the first A-D standing alone on the last "
             "line, any case")
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's port of ViewSpatial-Bench's rule"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    harness_sets = (("viewspatial", "choice"),)

    rule = staticmethod(viewspatial_label)


def viewspatial_official_label(text: str) -> str | None:
    """The label ViewSpatial-Bench's own ``evaluate.py`` reads in ``text``: the text after its last
    newline as written (``split("\\n")[-1]``, no strip, so a reply ending in a newline reads
    nothing), its first ``A``-``D`` standing alone, either case, upper-cased; or ``None``."""
    found = _WORD_LETTER.search(text.split("\n")[-1])
    return found.group(1).upper() if found else None


class ViewSpatialOfficialParser(RuleParser):
    """ViewSpatial-Bench's own ``evaluate.py`` (see :func:`viewspatial_official_label`)."""

    reads = ("ViewSpatial-Bench's evaluate.py: the first A-D standing alone, any case, on the text after the last newline as written (a reply ending in a "
             "newline reads nothing)")
    beside_official = "reads choice answers, which the official (point) parser does not read; ViewSpatial-Bench's own rule, the set's default"
    source = VIEWSPATIAL_BENCH
    harness = "ViewSpatial-Bench"

    rule = staticmethod(viewspatial_official_label)


@hookimpl
def register_parsers(register) -> None:
    """Contribute ViewSpatial-Bench's own rule and lmms-eval's port of it."""
    register(
        "viewspatial-official",
        ViewSpatialOfficialParser,
        description=(
            f"ViewSpatial-Bench's own rule: the first A-D word, any case, after the reply's last newline as written, no strip "
            f"(a reply ending in a newline reads nothing) ({VIEWSPATIAL_BENCH} evaluate.py extract_option, evaluate_vlm)"
        ),
    )
    register(
        "viewspatial",
        ViewSpatialParser,
        description=(
            f"lmms-eval's ViewSpatial-Bench rule: lmms-eval's reasoning-tag strip (--reasoning_tags <think>, <analysis>), then the "
            f"first A-D word on the last line (lmms_eval/tasks/viewspatial/utils.py extract_option @ {LMMS_EVAL}); "
            f"the set's own reading ({VIEWSPATIAL_BENCH} evaluate.py) is viewspatial-official"
        ),
    )
