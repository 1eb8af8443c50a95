"""One house as a task: the plain functions of one house that every engine runs, and what they hand back.

What it is for: ``make_house`` (write house ``index`` into the dataset folder, staged and renamed
into place) and ``make_house_files`` (make it in a private folder and return its files, for
workers that cannot see the output folder) are what this process, local worker processes
(``--jobs``) and Dask workers (:mod:`povagent.cluster.generation`) all run, so every engine
gives the same bytes. Both are idempotent and never raise for the house: a failure comes back
as a :class:`HouseFailure` in the :class:`HouseOutcome`. What it must not do: decide which houses
to make or in what order (that is :mod:`povagent.generate.dataset`), print, or import Dask;
nor load the renderer before a house is made: the process that only hands houses out (a worker
pool's parent, a Dask client) imports this module too, and the house pipeline's imports (the
mesh library, SciPy, Embree) cost it about a second of CPU for nothing.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from povagent.files.redaction import Redactor
from povagent.generate.judge import SurfaceJudge
from povagent.generate.record import GenerationOptions, HouseRecord, house_files, house_folder, read_record, write_house_atomically


@dataclass(frozen=True)
class HouseFailure:
    """A house that raised: its index, the dataset seed, and the error (type: message)."""

    index: int
    seed: int
    error: str


@dataclass
class HouseOutcome:
    """What one house task returns: its record, or its failure.

    ``files`` is set when the house came back as bytes (workers that cannot see the output
    folder); ``kept`` when it was already complete; ``cpu_seconds`` is measured, never written.
    """

    index: int
    record: HouseRecord | None = None
    failure: HouseFailure | None = None
    files: dict[str, bytes] | None = None
    kept: bool = False
    cpu_seconds: float = 0.0


def make_house(out: Path, options: GenerationOptions, index: int, judge: SurfaceJudge) -> HouseOutcome:
    """Make house ``index`` of the dataset in ``out`` unless it is complete; never raises for the house.

    Idempotent: run twice (or twice at once), the house is written once and its bytes are the same.
    """
    start = time.process_time()
    done = read_record(house_folder(out, index))
    if done is not None:
        return HouseOutcome(index, record=done, kept=True)
    try:
        from povagent.generate.house_pipeline import generate_house  # here: see the module's docstring

        record = write_house_atomically(
            Path(out),
            index,
            options,
            lambda folder: generate_house(folder, options.seed, index, options.frames, options.with_render, judge),
        )
    except Exception as exc:  # the house's own failure: recorded, the other houses go on
        return HouseOutcome(index, failure=_failure(options, index, exc), cpu_seconds=time.process_time() - start)
    return HouseOutcome(index, record=record, cpu_seconds=time.process_time() - start)


def make_house_files(options: GenerationOptions, index: int, judge: SurfaceJudge) -> HouseOutcome:
    """Make house ``index`` in a private temporary folder and return its files as bytes.

    For workers that cannot see the output folder: the caller writes the files with
    ``record.place_house_files``. Never raises for the house.
    """
    start = time.process_time()
    try:
        from povagent.generate.house_pipeline import generate_house  # here: see the module's docstring

        with tempfile.TemporaryDirectory(prefix="povagent-house-") as tmp:
            record = write_house_atomically(
                Path(tmp),
                index,
                options,
                lambda folder: generate_house(folder, options.seed, index, options.frames, options.with_render, judge),
            )
            files = house_files(house_folder(Path(tmp), index))
    except Exception as exc:
        return HouseOutcome(index, failure=_failure(options, index, exc), cpu_seconds=time.process_time() - start)
    return HouseOutcome(index, record=record, files=files, cpu_seconds=time.process_time() - start)


def _failure(options: GenerationOptions, index: int, exc: BaseException) -> HouseFailure:
    return HouseFailure(index, options.seed, Redactor().text(f"{type(exc).__name__}: {exc}"))
