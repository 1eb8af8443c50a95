"""Evaluation houses never reach a training set.

A house is recognised three ways: by the content of its pair file (a hash of the canonical JSON:
the objects, their boxes, cameras and sentences; the same house renamed or re-indented still
matches); by its frames (a house sharing any exploration frame or observer view, byte for byte,
with an evaluation house is one: a copy whose pair file gained a key, a re-saved float, a
reworded sentence or a nudged camera still shows the evaluation frames); and, for datasets this
project generated, by its generator identity (seed, house index), which matches a house
regenerated under another generator version. The exporter compares the houses it would export
with every known evaluation set: the release when it is in the local Hugging Face cache, and
any dataset passed with ``--exclude``.

Every file is untrusted: paths are kept inside the dataset, unreadable files are skipped (the
loader reports them), and nothing here raises on a malformed house.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from povagent.dataset.loader import house_folders, official_frame_paths
from povagent.dataset.paths import OutsideDatasetError, dataset_root, is_inside, observer_view_path
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_DOCUMENT_BYTES, open_regular, read_regular
from povagent.train.splits import house_index

#: The release's repository on the Hub (checked in the local cache only: never downloaded here).
RELEASE_REPO = "owl-owl/POVBench"


@dataclass(frozen=True)
class HouseIdentity:
    """How a house is recognised: its content hash and, when generated here, (seed, index)."""

    house_id: str
    content: str | None
    generated: tuple[int, int] | None
    #: sha256 of every exploration frame and observer view the house ships.
    frames: frozenset[str] = frozenset()


@dataclass
class EvaluationSets:
    """The houses of the known evaluation sets, and where each set came from."""

    sources: list[str] = field(default_factory=list)
    contents: dict[str, str] = field(default_factory=dict)
    generated: dict[tuple[int, int], str] = field(default_factory=dict)
    frames: dict[str, str] = field(default_factory=dict)

    def add(self, source: str, identities: Iterable[HouseIdentity]) -> int:
        """Add a set's houses; returns how many."""
        self.sources.append(source)
        n = 0
        for ident in identities:
            if ident.content is not None:
                self.contents.setdefault(ident.content, f"{source}:{ident.house_id}")
            for frame in ident.frames:
                self.frames.setdefault(frame, f"{source}:{ident.house_id}")
            if ident.generated is not None:
                self.generated.setdefault(ident.generated, f"{source}:{ident.house_id}")
            n += 1
        return n

    def match(self, ident: HouseIdentity) -> str | None:
        """The evaluation house ``ident`` matches, or ``None``."""
        hit = self.contents.get(ident.content) if ident.content is not None else None
        if hit is None and ident.generated is not None:
            hit = self.generated.get(ident.generated)
        if hit is None:
            shared = sorted(f for f in ident.frames if f in self.frames)
            if shared:
                hit = f"{self.frames[shared[0]]} (shares {len(shared)} frame(s))"
        return hit


def content_hash(pair_file: Path) -> str | None:
    """sha256 of a pair file's canonical JSON (key order and whitespace do not matter);
    ``None`` for a file that is not JSON (the loader reports it)."""
    try:
        data = json.loads(read_regular(pair_file, MAX_DOCUMENT_BYTES, what="pair file"))
        canonical = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    except (OSError, ValueError, RecursionError, ReadTargetError):
        return None
    # a lone surrogate (the loader refuses such a file) is hashed as its UTF-16 code unit, not a crash
    return hashlib.sha256(canonical.encode("utf-8", "surrogatepass")).hexdigest()


def _file_hash(path: Path) -> str | None:
    try:
        with open_regular(path, what="frame") as handle:
            return hashlib.file_digest(handle, "sha256").hexdigest()
    except (OSError, ReadTargetError):  # missing, a folder, a pipe, unreadable: no frame to compare
        return None


def frame_hashes(root: Path, folder: Path) -> frozenset[str]:
    """sha256 of every exploration frame (``exploration_images/*.png``) and every observer view
    (each pair's ``rgb_path``, resolved as the loader does) of the house at ``folder``; a path
    leading outside the dataset is not read."""
    real_root = dataset_root(root)
    files = [folder / p for p in official_frame_paths(folder, [])]
    try:
        pairs = json.loads(read_regular(folder / f"{folder.name}.json", MAX_DOCUMENT_BYTES, what="pair file"))
    except (OSError, ValueError, RecursionError, ReadTargetError):
        pairs = []
    for pair in pairs if isinstance(pairs, list) else []:
        rel = pair.get("rgb_path") if isinstance(pair, dict) else None
        if isinstance(rel, str):
            try:
                files.append(observer_view_path(real_root, folder, rel))
            except OutsideDatasetError:
                continue
    hashes = {_file_hash(f) for f in files if is_inside(real_root, f)}
    return frozenset(h for h in hashes if h is not None)


def generator_seed(root: Path) -> int | None:
    """The seed of a dataset this project generated (``meta.json``), else ``None``."""
    meta = root / "meta.json"
    try:
        data = json.loads(read_regular(meta, MAX_DOCUMENT_BYTES, what="dataset metadata"))
    except (OSError, ValueError, ReadTargetError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("generator"), dict):
        return None
    if data["generator"].get("name") != "povagent.generate" or not isinstance(data.get("seed"), int):
        return None
    return int(data["seed"])


def dataset_identities(root: Path) -> list[HouseIdentity]:
    """Every house of the dataset at ``root`` (its ``artifacts/<house>/<house>.json``)."""
    seed = generator_seed(root)
    out = []
    for folder in house_folders(root):
        pair_file = folder / f"{folder.name}.json"
        if not pair_file.is_file():
            continue
        idx = house_index(folder.name)
        generated = (seed, idx) if seed is not None and idx is not None else None
        out.append(HouseIdentity(folder.name, content_hash(pair_file), generated, frame_hashes(root, folder)))
    return out


def cached_release_root() -> Path | None:
    """The release's newest snapshot in the local Hugging Face cache, if one is there (offline)."""
    try:
        from huggingface_hub import scan_cache_dir
    except ImportError:  # pragma: no cover - huggingface_hub is a dependency
        return None
    try:
        info = scan_cache_dir()
    except Exception:  # no cache folder, or one huggingface_hub cannot read: nothing to check
        return None
    for repo in info.repos:
        if repo.repo_id == RELEASE_REPO and repo.repo_type == "dataset":
            revisions = sorted(repo.revisions, key=lambda r: r.last_modified, reverse=True)
            for rev in revisions:
                root = Path(rev.snapshot_path)
                for candidate in (root / "POVBench", root):
                    if (candidate / "artifacts").is_dir():
                        return candidate
    return None
