"""What made a house, and the one way a house becomes complete: renamed into place.

What it is for: a generated dataset grows one house at a time. Each house is written into a
folder of its own under ``OUT/.partial/`` with a small record of what made it (generator
version, seed, index, options, and the digest of them: ``_generated.json``), then renamed to
``OUT/artifacts/<house>``.
A house folder under ``artifacts/`` with a readable record is therefore complete, and anything
under ``.partial/`` is a house some process did not finish (it is removed and redone). The same
house written twice (a retried task whose first attempt was still running) is harmless: the
second rename finds the folder in place and its copy, byte-identical, is dropped. The records
are also how a re-run learns what is on disk: which houses to skip, whether the options asked
for are the options the dataset was made with, and the counts ``meta.json`` is written from.
The record's ``digest`` is the SHA-256 of its index and options: a house is a pure function of
them, so a record edited since (a changed seed renders another house) no longer matches it, and
``validate``, ``render`` and the active mode refuse it (:func:`record_problem`). It is a check
against edits and mix-ups, not a signature: whoever can write the record can write a new digest.
What it must not do: render anything, or record anything that differs between machines, worker
counts or runs (no times, hosts or pids), so a record is as reproducible as the house.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import uuid
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from povagent.dataset.paths import GENERATED_RECORD
from povagent.errors import DatasetError, ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, read_regular
from povagent.generate.deterministic_json import rounded, write_json

#: The record of what made a house, inside its folder (povagent's own files start with ``_``).
RECORD = GENERATED_RECORD
#: Where houses are written before they are complete (never inside ``artifacts/``, which the
#: loader reads).
PARTIAL = ".partial"
ARTIFACTS = "artifacts"


def house_id(index: int) -> str:
    """The release's house folder name: ``train_house_00000``."""
    return f"train_house_{index:05d}"


@dataclass
class HouseSummary:
    """What one house contributed: counts per direction and of files (no timings: pure)."""

    index: int
    house_id: str
    rooms: int
    objects: int
    reachable_frames: int
    pairs: int
    directions: dict[str, int] = field(default_factory=dict)
    renders: int = 0


@dataclass(frozen=True)
class GenerationOptions:
    """Everything that decides a house's bytes besides its index (the number of houses does not).

    ``judge_options`` are kept as recorded (secrets redacted), so they can be compared with a
    record on disk.
    """

    version: str
    seed: int
    frames: int
    with_render: bool
    judge: str
    judge_options: Mapping[str, Any] = field(default_factory=dict)

    def record(self) -> dict[str, Any]:
        """The options as a record stores them."""
        return {**asdict(self), "judge_options": dict(self.judge_options)}

    def difference(self, recorded: Mapping[str, Any]) -> str | None:
        """The first option (by name) whose value in ``recorded`` differs from this one, or None."""
        mine = json.loads(json.dumps(self.record()))  # the types a record read back has
        for name in mine:
            if recorded.get(name) != mine[name]:
                return name
        return None


def generation_digest(index: int, options: Mapping[str, Any]) -> str:
    """The SHA-256 (hex) of what made house ``index``: its index and the recorded options
    (generator version, seed, frames, with_render, judge and its options), as canonical JSON."""
    canonical = json.dumps({"index": index, "options": options}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(canonical.encode("ascii")).hexdigest()


@dataclass(frozen=True)
class HouseRecord:
    """A complete house: the options that made it, their digest and its summary (counts, no timings).

    ``digest`` is ``None`` for a record written before records carried one.
    """

    index: int
    options: dict[str, Any]
    summary: HouseSummary
    digest: str | None = None

    @classmethod
    def made(cls, index: int, options: GenerationOptions, summary: HouseSummary) -> HouseRecord:
        """The record of house ``index`` just made with ``options``, its digest computed."""
        # the values as the file holds them (floats rounded as written, JSON types)
        recorded = json.loads(json.dumps(rounded(options.record())))
        return cls(index, recorded, summary, generation_digest(index, recorded))

    def to_json(self) -> dict[str, Any]:
        """The record as written to ``_generated.json``."""
        written = {"index": self.index, "options": self.options, "summary": asdict(self.summary)}
        return written if self.digest is None else {**written, "digest": self.digest}


#: What ``validate`` says of a record without a digest (written by an earlier povagent), which
#: ``render`` and the active mode use as it is.
NO_DIGEST = "has no digest (written by an earlier povagent): its seed and options cannot be checked"


def record_problem(record: HouseRecord, house: str) -> tuple[str, str] | None:
    """The first field of ``record`` that does not describe the house folder named ``house`` as
    generated, and why (``("index", ...)``, ``("options.seed", ...)``, ``("digest", ...)``);
    ``None`` when the record holds. A record without a digest holds (:data:`NO_DIGEST`)."""
    if house_id(record.index) != house:
        return "index", f"{record.index} names house {house_id(record.index)}, not {house}"
    seed = record.options.get("seed")
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        return "options.seed", f"must be a non-negative integer, as every generated house's is (got {json.dumps(seed)[:40]})"
    if record.digest is not None and record.digest != generation_digest(record.index, record.options):
        return "digest", (
            "does not match the record's index and options (seed, generator version, frames, judge): the record was "
            "changed after the house was generated, so it no longer describes the house on disk; restore it or "
            "generate the dataset again"
        )
    return None


def house_folder(out: Path, index: int) -> Path:
    """Where house ``index`` lives once complete."""
    return Path(out) / ARTIFACTS / house_id(index)


def read_record(folder: Path) -> HouseRecord | None:
    """The record of a house folder, or None when it has none or it cannot be read (not complete)."""
    try:  # a pipe or a device planted as the record is refused, never waited on
        raw = json.loads(read_regular(folder / RECORD, MAX_DOCUMENT_BYTES, what="house record").decode("utf-8"))
    except (OSError, ValueError, ReadTargetError):
        return None
    return parse_record(raw)


def parse_record(raw: Any) -> HouseRecord | None:
    """A record from its parsed JSON, or None when it is not one."""
    if not isinstance(raw, dict):
        return None
    digest = raw.get("digest")
    try:
        # a digest of any other type is kept as its JSON text: it never matches, so it is refused
        kept = None if digest is None else digest if isinstance(digest, str) else json.dumps(digest)
        return HouseRecord(int(raw["index"]), dict(raw["options"]), HouseSummary(**raw["summary"]), kept)
    except (ValueError, TypeError, KeyError, OverflowError):
        return None


def complete_houses(out: Path) -> dict[int, HouseRecord]:
    """Every complete house under ``out/artifacts`` by index (folders without a record are not)."""
    found: dict[int, HouseRecord] = {}
    art = Path(out) / ARTIFACTS
    if not art.is_dir():
        return found
    for folder in sorted(art.iterdir()):
        record = read_record(folder) if folder.is_dir() else None
        if record is not None and folder.name == house_id(record.index):
            found[record.index] = record
    return found


def clear_partial(out: Path) -> None:
    """Remove ``.partial/`` (houses nobody will finish), first moving it aside in one rename.

    A task of an earlier, killed client may still be writing there: after the move its staging
    folder is gone from under it, so it can never rename a house it did not finish into place
    (``write_house_atomically`` checks that its folder is still the one it made).
    """
    out = Path(out)
    for leftover in sorted(out.glob(f"{PARTIAL}-removed-*")):
        shutil.rmtree(leftover, ignore_errors=True)
    partial = out / PARTIAL
    if partial.exists():
        aside = out / f"{PARTIAL}-removed-{uuid.uuid4().hex}"
        try:
            os.rename(partial, aside)
        except OSError:
            return
        shutil.rmtree(aside, ignore_errors=True)


def remove_half_written(out: Path, keep: set[int]) -> None:
    """Remove what unfinished runs left: ``.partial/`` and house folders with no record.

    Complete houses (``keep``) are never touched.
    """
    clear_partial(out)
    art = Path(out) / ARTIFACTS
    kept_names = {house_id(i) for i in keep}
    if art.is_dir():
        for folder in sorted(art.iterdir()):
            if folder.name not in kept_names and read_record(folder) is None:
                shutil.rmtree(folder) if folder.is_dir() else folder.unlink()


def write_house_atomically(
    out: Path, index: int, options: GenerationOptions, write: Callable[[Path], HouseSummary]
) -> HouseRecord:
    """Run ``write(folder)`` into a fresh folder under ``.partial/``, add the record, rename it in.

    When another attempt completed the house first, its copy stays and this one is dropped (the
    bytes are the same by construction). Returns the house's record.
    """
    out = Path(out)
    staging, made = _staging(out, index)
    try:
        summary = write(staging)
        record = HouseRecord.made(index, options, summary)
        write_json(staging / RECORD, record.to_json())
        return _place(staging, made, house_folder(out, index), record)
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def place_house_files(out: Path, index: int, files: Mapping[str, bytes]) -> HouseRecord:
    """Write a house's files (relative path -> bytes, as a worker sent them) and rename it in.

    The files must include the record; a path leaving the house folder is refused.
    """
    out = Path(out)
    staging, made = _staging(out, index)
    try:
        for rel, data in sorted(files.items()):
            target = (staging / rel).resolve()
            if not target.is_relative_to(staging.resolve()):
                raise DatasetError(f"house {index}: a worker sent a file outside the house folder ({rel!r})")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        record = read_record(staging)
        if record is None or record.index != index:
            raise DatasetError(f"house {index}: the files a worker sent have no readable {RECORD}")
        return _place(staging, made, house_folder(out, index), record)
    finally:
        if staging.exists():
            shutil.rmtree(staging, ignore_errors=True)


def house_files(folder: Path) -> dict[str, bytes]:
    """Every file under a house folder, by path relative to it (what a worker sends back)."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


#: The file a staging folder is born with, holding its token: a folder recreated under the same
#: name (a writer's ``mkdir(parents=True)`` after another run cleared ``.partial/``, even on a
#: reused inode number) lacks it, so a house missing its first files is never placed.
STAGING_TOKEN = ".staging"


def _staging(out: Path, index: int) -> tuple[Path, str]:
    """A fresh staging folder for house ``index`` and the token written into it first."""
    token = uuid.uuid4().hex
    staging = out / PARTIAL / f"{house_id(index)}.{token}"
    staging.mkdir(parents=True)
    (staging / STAGING_TOKEN).write_text(token)
    return staging, token


def _place(staging: Path, made: str, final: Path, record: HouseRecord) -> HouseRecord:
    try:
        still_ours = (staging / STAGING_TOKEN).read_text() == made
        (staging / STAGING_TOKEN).unlink()
    except OSError:
        still_ours = False
    if not still_ours:
        raise RuntimeError(f"{staging} was removed while the house was written (another run cleared .partial/)")
    final.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.rename(staging, final)  # atomic on one filesystem; fails when ``final`` is a full folder
    except OSError:
        done = read_record(final)
        if done is None:
            raise
        return done
    return record
