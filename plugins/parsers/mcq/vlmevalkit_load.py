"""What every VLMEvalKit rule reads: the reply as VLMEvalKit's own ``load`` hands it over.

VLMEvalKit never scores a reply as the model wrote it. At the pinned commit
(:data:`~povagent_plugins.parsers.mcq.upstream.VLMEVALKIT`) inference writes the replies to the
prediction file, and each set's ``evaluate`` reads that file back with ``vlmeval.smp.load``:
``pd.read_excel(f)`` for ``.xlsx``, ``pd.read_csv(f, sep='\\t')`` for ``.tsv``, neither passing
``na_values`` nor ``keep_default_na`` (so pandas' defaults apply, as they do to every set's path:
``eval_mcq_score`` for ViewSpatial-Bench, MindCube, MMSI-Bench and OmniSpatial, ``_3DSRBench`` and
``VsiBench``). It then writes every ``prediction`` with ``str()``. A cell that is exactly one of
pandas' default missing-value strings (its ``STR_NA_VALUES``: ``N/A``, ``NA``, ``None``,
``NULL``, ``nan``, an empty cell...; matched as written, so ``" N/A"`` and ``"none"`` stay text)
is NaN, and ``str(NaN)`` is ``"nan"``: VLMEvalKit's rules read ``"nan"`` there, so ``"N/A"``
names no option though the spatial-bench rule alone would read its ``A``.

The option cells go the same way: VLMEvalKit's exact matching builds a question's choices from
its ``A``-``Z`` cells that pandas does not read as missing (``build_choices``), so an option whose
text is ``"None"`` or ``"NA"`` is no choice there (the options after it stay):
:func:`options_as_vlmevalkit_loads`, which the rule reading option texts (``vlmevalkit-exact``)
applies; the spatial-bench rule reads no options.

Every VLMEvalKit rule parser applies :func:`as_vlmevalkit_loads` first and says so with
:data:`LOAD_FILTER` (``harness_filter``); the set's own rules and lmms-eval's, which never read
a reply through pandas, do not. Pure: text in, text out.
"""

from __future__ import annotations

from typing import ClassVar

from povagent.answers.spec import AnswerSpec, ParsedAnswer
from povagent_plugins.parsers.mcq.rule import RuleParser
from povagent_plugins.parsers.mcq.upstream import VLMEVALKIT

#: The cells ``pd.read_csv`` and ``pd.read_excel`` read as missing by default (pandas'
#: ``STR_NA_VALUES``, checked on pandas 3.1.1; VLMEvalKit's requirements pin no pandas version).
PANDAS_MISSING = frozenset(
    {
        "",
        "#N/A",
        "#N/A N/A",
        "#NA",
        "-1.#IND",
        "-1.#QNAN",
        "-NaN",
        "-nan",
        "1.#IND",
        "1.#QNAN",
        "<NA>",
        "N/A",
        "NA",
        "NULL",
        "NaN",
        "None",
        "n/a",
        "nan",
        "null",
    }
)
#: What ``str()`` makes of the NaN pandas reads there.
AS_MISSING = "nan"
#: How a rule says it reads the reply through VLMEvalKit's ``load`` (``harness_filter``).
LOAD_FILTER = "VLMEvalKit's load: a reply pandas reads as missing (N/A, NA, None, NULL, nan, empty...) is 'nan'"


def as_vlmevalkit_loads(reply: str) -> str:
    """The reply as VLMEvalKit's ``evaluate`` hands it to its rule: ``"nan"`` where pandas reads
    the cell as missing, else as written."""
    return AS_MISSING if reply in PANDAS_MISSING else reply


def options_as_vlmevalkit_loads(options: tuple[tuple[str, str], ...]) -> tuple[tuple[str, str], ...]:
    """The options VLMEvalKit's ``build_choices`` keeps: those whose text pandas does not read as
    missing, in order. An empty text stays: it is a label logged without its text (an lmms-eval
    log, a prompt listing none), not an empty cell (a VLMEvalKit file's options end at one)."""
    return tuple((label, text) for label, text in options if not text or text not in PANDAS_MISSING)


class VlmevalkitRuleParser(RuleParser):
    """A VLMEvalKit rule: its :meth:`label` reads the reply as VLMEvalKit's ``load`` hands it over
    (module docstring)."""

    source: ClassVar[str] = VLMEVALKIT
    harness: ClassVar[str] = "VLMEvalKit"
    harness_filter: ClassVar[str] = LOAD_FILTER

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        """The rule's label in the reply as VLMEvalKit loads it; never raises."""
        return super().parse(as_vlmevalkit_loads(text or ""), spec)
