"""A generated house rebuilt from its record, kept per process, rendered to PNG bytes.

What it is for: every house of a povagent-generated dataset carries the record of what made
it (``_generated.json``: generator version, seed, index), and the house is a pure function of
(seed, index). Rebuilding it gives the renderer the frames were drawn with, so any camera can
be rendered, and the camera of an exploration frame or an observer view reproduces that PNG
byte for byte (same renderer, same encoder settings as the writer). Houses are kept in a small
per-process cache (least recently used out), since a rebuild costs far more than a view.
What it must not do: accept a house this generator version did not make (the public release
has no 3D scene: its houses have no record), or a record changed since (its digest no longer
matches: another seed renders another house), or read outside the dataset folder.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path

from povagent.errors import DatasetError
from povagent.generate.dataset import GENERATOR_VERSION
from povagent.generate.frame_png import encode_planes_png
from povagent.generate.house_pipeline import BuiltHouse, build_house
from povagent.generate.record import ARTIFACTS, RECORD, read_record, record_problem
from povagent.geometry.camera import Camera

#: Houses kept rebuilt per process (a rebuilt house holds its embree scenes: tens of MB).
CACHE_SIZE = 4


@dataclass
class ActiveHouse:
    """One rebuilt house: its model and renderer, the dataset seed and its index."""

    dataset_dir: Path
    house_id: str
    seed: int
    index: int
    built: BuiltHouse
    lock: threading.Lock

    def render_png(self, camera: Camera) -> bytes:
        """The PNG bytes of ``camera``'s view, encoded exactly as the writer encodes frames."""
        with self.lock:  # the renderer caches ray grids per size: one render at a time per house
            planes = self.built.renderer.render_planes(camera)
        # the pixels of ``render(camera).rgb``, encoded by the writer's encoder: the bytes of the
        # dataset's PNGs
        return encode_planes_png(planes, camera.height, camera.width)


_CACHE: OrderedDict[tuple[str, str], ActiveHouse] = OrderedDict()
_CACHE_LOCK = threading.Lock()


def house_folder(dataset_dir: Path, house: str) -> Path:
    """The folder of ``house`` inside the dataset, refusing a name that would leave it."""
    root = Path(dataset_dir).resolve()
    if not house or "/" in house or "\\" in house or house in (".", "..") or len(house) > 200:
        raise DatasetError(f"{dataset_dir}: {house[:80]!r} is not a house name (train_house_NNNNN)")
    folder = root / ARTIFACTS / house
    if not folder.resolve().is_relative_to(root):
        raise DatasetError(f"{dataset_dir}: house {house[:80]!r} lies outside the dataset folder")
    return folder


def check_generated(dataset_dir: Path, house: str) -> tuple[int, int]:
    """``(seed, index)`` of a house this generator version made, else one line saying why not."""
    folder = house_folder(dataset_dir, house)
    if not folder.is_dir():
        raise DatasetError(f"{dataset_dir}: no house {house} under {ARTIFACTS}/")
    record = read_record(folder)
    if record is None:
        raise DatasetError(
            f"{folder}: no readable {RECORD}: the active mode needs a dataset made by `povagent generate` "
            f"(the public release carries no 3D scene to render)"
        )
    version = record.options.get("version")
    if version != GENERATOR_VERSION:
        raise DatasetError(
            f"{folder / RECORD}: made by generator version {version!r}, this povagent renders version "
            f"{GENERATOR_VERSION!r} only: generate the dataset again with this version"
        )
    wrong = record_problem(record, house)  # a record without a digest (an earlier povagent's) is used as it is
    if wrong is not None:
        field, why = wrong
        raise DatasetError(f"{folder / RECORD}: field {field} {why}")
    return int(record.options["seed"]), record.index


def house_for(dataset_dir: Path, house: str) -> ActiveHouse:
    """The rebuilt house (from the per-process cache when it is there)."""
    key = (str(Path(dataset_dir).resolve()), house)
    with _CACHE_LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            return hit
    seed, index = check_generated(dataset_dir, house)
    built = build_house(seed, index)
    made = ActiveHouse(Path(key[0]), house, seed, index, built, threading.Lock())
    with _CACHE_LOCK:
        made = _CACHE.setdefault(key, made)
        _CACHE.move_to_end(key)
        while len(_CACHE) > CACHE_SIZE:
            _CACHE.popitem(last=False)
    return made


def forget_houses() -> None:
    """Empty the per-process cache (benchmarks measure a rebuild with it)."""
    with _CACHE_LOCK:
        _CACHE.clear()


def render_view(dataset_dir: Path, house: str, camera: Camera) -> bytes:
    """PNG bytes of ``camera`` in house ``house`` of a povagent-generated dataset.

    The camera of an exploration frame (``exploration_log.json``) or of a pair's observer
    view (the house file's ``camera``) gives that image's bytes exactly. A house not made by
    this generator version is a :class:`~povagent.errors.DatasetError` saying why.
    """
    return house_for(dataset_dir, house).render_png(camera)
