"""The ``povbench`` and ``generated`` formats: a folder in the POVBench release layout, the published
release (``owl-owl/POVBench``) or a set ``povagent generate`` wrote (its houses carry
``_generated.json``), both read by the release loader (:mod:`povagent.dataset.loader`) and scored
by the paper's metric. Neither is named in a pipeline: a folder with no ``dataset.format`` is
looked at (:attr:`~povagent.dataset.formats.DatasetFormat.detect`), and the release layout takes
any folder no other format claims."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from povagent import hookimpl
from povagent.dataset.formats import DatasetFormat, DocsRow, FormatRead
from povagent.dataset.set_interface import EvaluationSet
from povagent.errors import DatasetError


def read_release(request: FormatRead) -> EvaluationSet:
    """The release-layout set at ``request.path`` (:func:`povagent.dataset.loader.load_dataset`)."""
    from povagent.dataset.loader import load_dataset

    return load_dataset(request.path, strict=request.strict, frame_size=_frame_size(request), check_images=request.check_images)


def release_problems(request: FormatRead) -> list:
    """Every problem of the release-layout folder (:func:`povagent.dataset.validate.validate_dataset`)."""
    from povagent.dataset.validate import validate_dataset

    return validate_dataset(request.path, _frame_size(request), request.warnings)


def _frame_size(request: FormatRead) -> tuple[int, int]:
    """The size every frame must have: ``options`` ``width`` and ``height`` (default 512 x 512)."""
    size = (request.options.get("width", 512), request.options.get("height", 512))
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 1 for v in size):
        raise DatasetError(f"{request.path}: dataset.options width and height must be positive integers, got {size[0]!r} x {size[1]!r}")
    return size


def is_generated(root: Path) -> bool:
    """Whether a house of ``root`` carries the generator's record (``artifacts/*/_generated.json``)."""
    from povagent.dataset.paths import GENERATED_RECORD as RECORD

    artifacts = root / "artifacts"
    return artifacts.is_dir() and any((house / RECORD).is_file() for house in artifacts.iterdir() if house.is_dir())


def _pair_entry(index: str) -> str:
    """A pair entry is named by its position in its house's list of pairs."""
    return f"$[{index}]"


POVBENCH = DatasetFormat(
    key="povbench",
    description="POVBench: the paper's release, a point for a sentence about another's point of view in a house",
    read=read_release,
    validate=release_problems,
    record_id=_pair_entry,
    answer_type="point",
    official_parser="official",
    official_scorer="official",
    source="owl-owl/POVBench@main (scored as mimo-owl/povbench-eval scores it)",
    licence="see the dataset card (the evaluation code is MIT)",
    docs_row=DocsRow(
        name="POVBench",
        where="[`owl-owl/POVBench`](https://huggingface.co/datasets/owl-owl/POVBench) (`dataset: {hub: owl-owl/POVBench}`)",
        path="the release folder",
        how_to="how-to/release.md",
    ),
    option_names=("width", "height"),
    detect=lambda root: True,  # any folder no other format claims (a missing one: the loader says so)
    detect_order=1000,
)

# the release layout, read, checked and scored as the release is: only what it is and how it is found differ
GENERATED = replace(
    POVBENCH,
    key="generated",
    description="A generated set: houses povagent generate built, written in the release layout",
    source="povagent generate (the paper's five-stage pipeline)",
    licence="yours (the assets' licences apply to the frames)",
    docs_row=DocsRow(name="a generated set", where="`povagent generate`", path="the folder it wrote", how_to="tutorials/first-dataset.md"),
    detect=is_generated,
    detect_order=500,
)


@hookimpl
def register_dataset_formats(register) -> None:
    """Contribute the release layout's formats: the POVBench release and generated sets."""
    register(POVBENCH.key, POVBENCH, description=POVBENCH.description)
    register(GENERATED.key, GENERATED, description=GENERATED.description)
