"""Shards of bounded size, planned before anything is written, each written atomically.

The plan is a pure function of the examples that will be written (their ids and estimated
sizes, in a fixed order): consecutive examples of one split fill a shard until the next one
would pass the size cap. A shard is one unit of work: a process, a local pool or a cluster task
writes it to a temporary file in the same folder and renames it into place, so a shard file that
exists is complete. Resuming re-plans, finds the plan unchanged, and writes only the shards not
yet there; a killed export leaves at most temporary files, which the next run removes.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from povagent.errors import PovagentError

#: The default bound on one shard's size, as the issue asks (Hub-friendly Parquet files).
DEFAULT_SHARD_BYTES = 500 * 1024 * 1024



@dataclass(frozen=True)
class PlannedExample:
    """An example the plan places: its id, house, split and estimated size in bytes."""

    id: str
    house_id: str
    split: str
    size: int


@dataclass(frozen=True)
class Shard:
    """One shard: its file name (relative to the format's folder) and the examples it holds."""

    name: str
    split: str
    examples: tuple[PlannedExample, ...]

    @property
    def houses(self) -> tuple[str, ...]:
        """The houses with at least one example here, in order."""
        return tuple(dict.fromkeys(e.house_id for e in self.examples))

    @property
    def size(self) -> int:
        """The estimated size in bytes."""
        return sum(e.size for e in self.examples)


def plan_shards(examples: Sequence[PlannedExample], max_bytes: int, suffix: str) -> list[Shard]:
    """Cut ``examples`` (already in export order) into shards of at most ``max_bytes`` each.

    An example larger than the cap gets a shard of its own. Names follow the Hub's
    ``SPLIT-00000-of-00003.SUFFIX`` convention.
    """
    by_split: dict[str, list[list[PlannedExample]]] = {}
    for ex in examples:
        groups = by_split.setdefault(ex.split, [[]])
        current = groups[-1]
        if current and sum(e.size for e in current) + ex.size > max_bytes:
            groups.append([ex])
        else:
            current.append(ex)
    shards = []
    for split, groups in by_split.items():
        for i, group in enumerate(groups):
            shards.append(Shard(f"{split}-{i:05d}-of-{len(groups):05d}.{suffix}", split, tuple(group)))
    return shards


class ExportWriteError(PovagentError):
    """A file of an export cannot be written (a full disk, a read-only place); the message
    names the file and why. A link planted where the export writes is a
    :class:`~povagent.errors.WriteTargetError`."""


@contextmanager
def atomic_file(path: Path, mode: str = "wb", inside: Path | None = None, unique: bool = False) -> Iterator[IO[Any]]:
    """Write ``path`` through a temporary file beside it, fsync it, and rename it into place.

    Through :class:`~povagent.files.confined_write.ConfinedFolder`: ``inside`` (default:
    ``path``'s folder) is the folder the user named, and no link below it is followed, so a
    link planted in an export folder cannot carry a write elsewhere; the rename replaces a
    link at ``path`` itself. ``unique``: the temporary name carries the process and thread
    (for a file several cluster workers may write at once). On any error the temporary file
    is removed and ``path`` is left as it was; a disk error is an :class:`ExportWriteError`
    naming ``path``.
    """
    from povagent.files.confined_write import ConfinedFolder

    root = inside if inside is not None else path.parent
    try:
        rel = path.parent.relative_to(root).as_posix()
    except ValueError:
        raise ExportWriteError(f"{path}: outside {root}; not written") from None
    try:
        with ConfinedFolder(root, "" if rel == "." else rel) as folder, folder.staged(
            path.name, encoding=None if "b" in mode else "utf-8", unique=unique
        ) as staged:
            yield staged.file
            staged.commit(fsync=True)
    except OSError as exc:
        raise ExportWriteError(f"{path}: cannot be written ({exc.strerror or exc})") from None


def remove_stale_temporaries(folder: Path) -> int:
    """Remove the temporary files a killed export left in ``folder`` (recursively, links not
    followed); returns how many."""
    if not folder.is_dir():
        return 0
    n = 0
    for path in folder.rglob("*.tmp"):
        if path.is_file() and not path.is_symlink():
            path.unlink(missing_ok=True)
            n += 1
    return n
