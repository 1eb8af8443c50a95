"""The ``3dsrbench-lmms`` parser: lmms-eval's ``3dsrbench`` rule, after lmms-eval's reasoning-tag strip
(3DSRBench's authors score with VLMEvalKit, whose reading is ``vlmevalkit-exact``: the set's default).

The rule (``extract_answer`` and ``process_results`` of lmms-eval's
``lmms_eval/tasks/3dsrbench/utils.py``), after lmms-eval's reasoning strip: the first pattern
that matches anywhere gives its capital ``A``-``D`` (its first match, not its last):
the reply opening with X and then a period, space or ``)``; the reply being X alone;
"answer" then spaces or colons then X; "the answer is X"; "my answer is X"; ``(X)``; ``X.``;
finally any X standing alone. So "A chair blocks the view, so the answer is B." is ``A``.
"""

from __future__ import annotations

import re

from povagent import hookimpl
from povagent_plugins.parsers.mcq.lmms_reasoning import strip_reasoning_blocks
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL

_IN_ORDER = tuple(
    re.compile(p)
    for p in (
        r"^([A-D])[\.\s\)]",
        r"^([A-D])$",
        r"[Aa]nswer[:\s]+([A-D])",
        r"[Tt]he answer is[:\s]+([A-D])",
        r"[Mm]y answer is[:\s]+([A-D])",
        r"\(([A-D])\)",
        r"([A-D])\.",
        r"\b([A-D])\b",
    )
)


def threedsrbench_lmms_label(text: str) -> str | None:
    """The label lmms-eval's 3DSRBench rule reads in ``text`` (module docstring), or ``None``."""
    text = strip_reasoning_blocks(text)
    if not text:
        return None
    for pattern in _IN_ORDER:
        if found := pattern.search(text):
            return found.group(1)
    return None


class ThreeDSRBenchLmmsParser(RuleParser):
    """lmms-eval's 3DSRBench rule (module docstring)."""

    reads = "lmms-eval's 3dsrbench: its reasoning-tag strip (<think>, <analysis> blocks), then the first of eight capital A-D patterns that matches"
    beside_official = "reads choice answers, which the official (point) parser does not read; lmms-eval's reading of 3DSRBench"
    source = LMMS_EVAL
    harness = "lmms-eval"
    harness_filter = "lmms-eval's reasoning-tag strip"
    harness_sets = (("3dsrbench", "choice-3dsrbench"),)

    rule = staticmethod(threedsrbench_lmms_label)


@hookimpl
def register_parsers(register) -> None:
    """Contribute the 3dsrbench-lmms parser."""
    register(
        "3dsrbench-lmms",
        ThreeDSRBenchLmmsParser,
        description=(
            f"lmms-eval's 3DSRBench rule: lmms-eval's reasoning-tag strip (--reasoning_tags <think>, <analysis>), then the first of "
            f"eight A-D patterns (lmms_eval/tasks/3dsrbench/utils.py extract_answer @ {LMMS_EVAL}); the set's own default is "
            f"vlmevalkit-exact with the choice-3dsrbench scorer"
        ),
    )
