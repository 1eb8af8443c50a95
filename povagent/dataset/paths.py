"""Where a dataset may point: every file it names resolves inside the dataset folder.

A dataset is untrusted input. Its JSON names image files (``image_path``, ``rgb_path``), and an
image that is opened is base64-sent to a model: a path that is absolute, climbs out with
``../``, or runs through a symlink to somewhere else would send that file (``/etc/passwd``, a
private photo) to a third party. Every path is resolved (symlinks followed) and must land inside
the dataset root before anything opens it. Paths that climb and come back (``../house_b/x.png``)
and symlinks between files of the dataset are fine: the rule is where a path leads. As written,
too, a path must stay inside: ``..`` parts that climb out through a symlinked folder and come
back resolve inside, yet the same text joined to another folder (an export laying out files)
leads out of it.

This module decides where a path leads; it never opens a file.
"""

from __future__ import annotations

import os
from pathlib import Path, PurePosixPath, PureWindowsPath

#: The generator's record of what made a house, inside the house's folder (povagent's own files
#: start with ``_``): named here, low in the house, so telling a generated set from a release
#: does not import the generator.
GENERATED_RECORD = "_generated.json"

#: Longest path text quoted back in a message (a hostile dataset may hold megabytes).
_SHOWN = 120


class OutsideDatasetError(ValueError):
    """A path a dataset names leads outside the dataset folder (the message says how)."""


def shown(value: str) -> str:
    """``value`` quoted for a message, cut to a readable length."""
    text = value if len(value) <= _SHOWN else value[: _SHOWN - 3] + "..."
    return repr(text)


def dataset_root(root: Path) -> Path:
    """The real location of a dataset folder (symlinks resolved): what paths are checked against.

    A release fetched from the Hub lives in a snapshot of the Hugging Face cache, whose files
    are symlinks into the same repository's ``blobs/``
    (``<cache>/datasets--owl-owl--POVBench/snapshots/<commit>/...`` -> ``../../blobs/<sha>``):
    for a folder inside such a snapshot, the repository's cache folder is the boundary, so the
    snapshot's own blobs are inside and anything else still is not.
    """
    real = root.resolve()
    for parent in (real, *real.parents):
        if parent.parent.name == "snapshots" and parent.parent.parent.name.startswith("datasets--"):
            repo = parent.parent.parent
            if (repo / "blobs").is_dir():
                return repo
            break
    return real


def is_inside(real_root: Path, path: Path) -> bool:
    """Whether ``path``, with every symlink followed, is inside ``real_root``."""
    return path.resolve().is_relative_to(real_root)


def confined(real_root: Path, base: Path, rel: str, what: str = "image path", real_base: Path | None = None) -> Path:
    """``base / rel``, checked to resolve inside ``real_root``; raises :class:`OutsideDatasetError`.

    ``rel`` must be relative (to the house folder ``base``, as the release writes it); an
    absolute path is refused even when it happens to point inside the dataset, because the
    same dataset moved elsewhere would point outside it. ``real_base``: ``base.resolve()``
    when the caller has it already (a house's frames share their folder: resolved once).
    """
    if "\x00" in rel:
        raise OutsideDatasetError(f"{what} {shown(rel)} contains a NUL character; not opened")
    if PurePosixPath(rel).is_absolute() or PureWindowsPath(rel).is_absolute() or PureWindowsPath(rel).drive:
        raise OutsideDatasetError(
            f"{what} {shown(rel)} is absolute: paths in a dataset are relative to the house folder "
            "and stay inside the dataset; not opened"
        )
    path = base / rel
    spelled_inside = Path(os.path.normpath((base.resolve() if real_base is None else real_base) / rel)).is_relative_to(real_root)
    if not is_inside(real_root, path):
        # Spelled inside but resolving outside: a symlink on the way leads out.
        via = " through a symlink" if spelled_inside else ""
        raise OutsideDatasetError(f"{what} {shown(rel)} leads outside the dataset folder{via}; not opened")
    if not spelled_inside:
        # Resolving inside but spelled outside: a symlinked folder deeper than it looks, climbed
        # back out of with ``..``. Whoever joins the text to another folder (an export laying out
        # files) would land outside that folder, so the text itself must stay inside too.
        raise OutsideDatasetError(
            f"{what} {shown(rel)} climbs out of the dataset folder as written (its '..' parts pass "
            "through a symlinked folder and come back); write the path without climbing through the link"
        )
    return path


def observer_view_path(real_root: Path, house_folder: Path, rel: str, real_folder: Path | None = None) -> Path:
    """Where an ``rgb_path`` is: relative to the house folder, or (as some releases write it)
    to the dataset root; both candidates must stay inside the dataset. ``real_folder``: the
    house folder resolved, when the caller has it."""
    path = confined(real_root, house_folder, rel, real_base=real_folder)
    if path.exists():
        return path
    alt = confined(real_root, house_folder.parent.parent, rel)
    return alt if alt.exists() else path
