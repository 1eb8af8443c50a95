"""The ``mmsi-circular`` format: MMSI-Bench's circular split, each question of
``MMSI_Bench.parquet`` asked four times with its options rotated
(:mod:`povagent.dataset.choice_sets.mmsi_circular_copies`), in the set's own wording, read by its own
rule and scored by ``choice-mmsi-circular``: a question right only when all four copies are.
VLMEvalKit's ``MMSIBench_circular`` reads the copies with its exact-matching rule
(``vlmevalkit-exact``), scored the same way."""

from __future__ import annotations

from povagent import hookimpl
from povagent.dataset.choice_sets import ChoiceFiles, choice_set_format
from povagent.dataset.choice_sets.mmsi_circular_copies import read_mmsi_circular
from povagent.dataset.formats import DocsRow
from povagent_plugins.formats.mmsi import MMSI
from povagent_plugins.parsers.mcq.upstream import MMSI_BENCH

FILES = ChoiceFiles(key="mmsi-circular", records=read_mmsi_circular, repository_file="MMSI_Bench.parquet")

MMSI_CIRCULAR = choice_set_format(
    FILES,
    description="MMSI-Bench's circular split: each question asked four times, its options rotated; right only when all four are",
    official_parser="mmsi-official",
    official_scorer="choice-mmsi-circular",
    prompt_profile=MMSI.prompt_profile,
    source=MMSI_BENCH,
    licence=MMSI.licence,
    docs_row=DocsRow(
        name="MMSI-Bench (circular)",
        where=MMSI.docs_row.where,
        path="`MMSI_Bench.parquet`, each question asked four times with its options rotated",
        how_to="how-to/mmsi-bench.md",
    ),
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute MMSI-Bench's circular split."""
    register(MMSI_CIRCULAR.key, MMSI_CIRCULAR, description=MMSI_CIRCULAR.description)


__all__ = ["FILES", "MMSI_CIRCULAR"]
