"""External multiple-choice perspective-taking sets, read from the user's download in their
published formats: ViewSpatial-Bench (:mod:`.viewspatial`), MindCube (:mod:`.mindcube`) and
3DSRBench (:mod:`.srbench3d`).

Each is a dataset format plugin (``povagent_plugins.formats``) whose reader is a
:class:`ChoiceReader`: ``dataset: {path: F, format: NAME}`` names the set's file;
:func:`read_choice_set` reads it into a runnable :class:`~.external.ChoiceSet` (what
:func:`povagent.dataset.evaluation_set.open_evaluation_set` returns for such a format) and
``povagent validate F --format NAME`` lists its problems. Only what every choice set shares lives
here (a set's own file layout is its :class:`ChoiceFiles`). Nothing here fetches a set.
"""

from __future__ import annotations

import shutil
import tempfile
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from povagent.dataset.choice_sets.external import ChoiceSet, ImageLookups, Item, choice_instance, item_frames
from povagent.dataset.formats import DatasetFormat, FormatRead, registered_formats
from povagent.dataset.problems import Problem
from povagent.errors import DatasetError

#: The answer type every item of these sets asks for (its strategy and scorers are a pipeline's
#: defaults on such a set: :func:`povagent.config.plugin_checks.resolve_components`).
SET_ANSWER_TYPE = "choice"


def record_by_id(item_id: str) -> str:
    """How most sets' problems name a record: ``record 12`` (the set's own id, or its row)."""
    return f"record {item_id}"


@dataclass(frozen=True)
class ChoiceFiles:
    """How one multiple-choice set's file is read; the rest (images confined to one folder,
    embedded images cached, each item an instance) is every choice set's."""

    #: The set's name, as its instances carry it (``dataset.format``).
    key: str
    #: Reads the file: ``records(file, cache) -> (items, problems)`` (``cache``: where embedded
    #: images may be written); never opens an image.
    records: Callable[[Path, Path], tuple[list[Item], list[Problem]]]
    #: How a problem names a record by its id (``"$[3]"``, ``"record 3"``).
    record_id: Callable[[str], str] = record_by_id
    #: Where the set's file sits in its repository, when ``dataset.path`` may name the repository
    #: folder instead (ViewSpatial-Bench's image paths are relative to the repository root,
    #: ``ViewSpatial-Bench/scannetv2_val/...`` beside ``eval/ViewSpatial-Bench.json``).
    repository_file: str | None = None
    #: What a problem of an image that does not exist adds, for a set whose image paths are
    #: relative to somewhere other than its file's folder.
    images_hint: str | None = None


class ChoiceReader:
    """A :class:`~povagent.dataset.formats.DatasetFormat` reader for a multiple-choice set:
    ``ChoiceReader(files)(FormatRead(path, images=...))`` is :func:`read_choice_set`'s set."""

    def __init__(self, files: ChoiceFiles) -> None:
        self.files = files

    def __call__(self, request: FormatRead) -> ChoiceSet:
        """The set ``request`` names (``options`` are refused: a choice set has none)."""
        if request.options:
            raise DatasetError(f"{request.path}: a {self.files.key} set takes no dataset.options (got {', '.join(map(str, request.options))})")
        return read_choice_set(request.path, self.files, images=request.images)

    def problems(self, request: FormatRead) -> list[Problem]:
        """Every problem of the set ``request`` names (:func:`check_choice_set`)."""
        return check_choice_set(request.path, self.files, request.images)


def choice_set_format(files: ChoiceFiles, **fields: Any) -> DatasetFormat:
    """The dataset format of the multiple-choice set ``files`` reads: its reader, its problems,
    how they name a record and its answer type are every choice set's; ``fields`` are the rest
    of :class:`~povagent.dataset.formats.DatasetFormat` (description, official rule, profile, ...)."""
    reader = ChoiceReader(files)
    return DatasetFormat(key=files.key, read=reader, validate=reader.problems, record_id=files.record_id, answer_type=SET_ANSWER_TYPE, **fields)


def load_choice_set(file: str | Path, format: str, *, images: str | Path | None = None, cache_dir: str | Path | None = None) -> ChoiceSet:
    """The set in ``file``, read as the registered multiple-choice format ``format``
    (:func:`read_choice_set`). :class:`~povagent.errors.DatasetError` for a format that is not a
    registered choice set."""
    return read_choice_set(file, _files(file, format), images=images, cache_dir=cache_dir)


def validate_choice_set(file: str | Path, format: str, images: str | Path | None = None) -> list[Problem]:
    """Every problem of the set in ``file``, read as the registered multiple-choice format
    ``format`` (:func:`check_choice_set`)."""
    try:
        files = _files(file, format)
    except DatasetError as exc:
        return [Problem(str(file), "", str(exc).removeprefix(f"{file}: "))]
    return check_choice_set(file, files, images)


def _files(file: str | Path, format: str) -> ChoiceFiles:
    from povagent.plugins import get_plugin_host

    formats = registered_formats(get_plugin_host())
    reader = formats[format].read if format in formats else None
    if not isinstance(reader, ChoiceReader):
        known = [k for k, f in formats.items() if isinstance(f.read, ChoiceReader)]
        raise DatasetError(f"{file}: unknown dataset format {format!r} (known: {', '.join(known)})")
    return reader.files


def read_choice_set(file: str | Path, files: ChoiceFiles, *, images: str | Path | None = None, cache_dir: str | Path | None = None) -> ChoiceSet:
    """The set in ``file``, read as ``files`` says, its image paths relative to (and confined to)
    the folder ``images`` (default: the file's folder); bad records are left out and named in
    ``problems``. ``file`` may be the set's repository folder where the set's image paths are
    relative to it (:attr:`ChoiceFiles.repository_file`): the file is then found in it, and it is the
    default ``images``. :class:`~povagent.errors.DatasetError` when the file cannot be read at all."""
    file = Path(file)
    if file.is_dir() and files.repository_file is not None:
        images = file if images is None else images
        file = file / files.repository_file
    if not file.is_file():
        raise DatasetError(f"{file}: not found (dataset.path of a {files.key} set names the set's file)")
    own_cache = cache_dir is None
    cache = Path(tempfile.mkdtemp(prefix="povagent-choices-")) if cache_dir is None else Path(cache_dir)
    items, problems = _read(file, files, cache)
    root = file.parent if images is None else Path(images)
    if not root.is_dir():
        raise DatasetError(f"{root}: not a folder (dataset.images names the folder a set's image paths are relative to)")
    from povagent.dataset.realworld_set import unknown_object

    instances = []
    lookups = ImageLookups(root)  # each image path resolved and checked once per set
    nowhere = unknown_object()  # the items' unknown observer and anchor: one object for the set
    for item in items:
        before = len(problems)
        frames = item_frames(root, item, str(file), files.record_id(item.id), problems, cache, lookups)
        if frames is not None:
            instances.append(choice_instance(files.key, item, frames, nowhere))
        elif files.images_hint is not None and images is None and problems[before:] and problems[-1].message.endswith("does not exist"):
            problems[-1] = Problem(problems[-1].file, problems[-1].json_path, f"{problems[-1].message} ({files.images_hint})")
    choice_set = ChoiceSet(root, file, files.key, problems, instances, cache_dir=cache)
    if own_cache:
        weakref.finalize(choice_set, shutil.rmtree, str(cache), True)
    return choice_set


def check_choice_set(file: str | Path, files: ChoiceFiles, images: str | Path | None = None) -> list[Problem]:
    """Every problem of the set in ``file`` (``povagent validate F --format NAME``): the records
    its reader leaves out, each image fully decoded too; a file that cannot be read at all is
    one problem."""
    from povagent.dataset.image_files import decode_fully

    try:
        loaded = read_choice_set(file, files, images=images)
    except DatasetError as exc:
        return [Problem(str(file), "", str(exc).removeprefix(f"{file}: "))]
    problems = list(loaded.problems)
    for instance in loaded.instances():
        for frame in instance.frames:
            try:
                decode_fully(frame.file)
            except (OSError, ValueError) as exc:
                problems.append(Problem(str(file), f"{files.record_id(instance.pair_id)}.images[{frame.index}]", f"image {frame.image_path!r} {exc}"))
    return problems


def _read(file: Path, files: ChoiceFiles, cache: Path) -> tuple[list[Item], list[Problem]]:
    from povagent.errors import ReadTargetError

    try:
        return files.records(file, cache)
    except ReadTargetError as exc:
        raise DatasetError(str(exc)) from None
    except OSError as exc:
        raise DatasetError(f"{file}: cannot be read: {exc}") from None


__all__ = [
    "SET_ANSWER_TYPE",
    "ChoiceFiles",
    "ChoiceReader",
    "ChoiceSet",
    "check_choice_set",
    "choice_set_format",
    "load_choice_set",
    "read_choice_set",
    "record_by_id",
    "validate_choice_set",
]
