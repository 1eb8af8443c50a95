"""External multiple-choice perspective-taking sets, read from the user's download in their
published formats: ViewSpatial-Bench (:mod:`.viewspatial`), MindCube (:mod:`.mindcube`) and
3DSRBench (:mod:`.srbench3d`).

``dataset: {path: F, format: viewspatial | mindcube | 3dsrbench}`` names the set's file;
:func:`load_choice_set` reads it into a runnable :class:`~.external.ChoiceSet` (what
:func:`povagent.dataset.evaluation_set.open_evaluation_set` returns for such a format) and
``povagent validate F --format NAME`` lists its problems. Nothing here fetches a set.
"""

from __future__ import annotations

import shutil
import tempfile
import weakref
from pathlib import Path

from povagent.dataset.choice_sets.external import ChoiceSet, ImageLookups, choice_instance, item_frames
from povagent.dataset.problems import Problem
from povagent.errors import DatasetError

#: The formats a set's file may be given in (``dataset.format``), each with the set's name.
CHOICE_FORMATS = {"viewspatial": "viewspatial", "mindcube": "mindcube", "3dsrbench": "3dsrbench", "mmsi": "mmsi", "omnispatial": "omnispatial"}

#: Where a set's file sits in its repository: ``dataset.path`` may name the repository folder
#: instead of the file (ViewSpatial-Bench's image paths are relative to the repository root,
#: ``ViewSpatial-Bench/scannetv2_val/...`` beside ``eval/ViewSpatial-Bench.json``).
REPOSITORY_FILES = {"viewspatial": "eval/ViewSpatial-Bench.json", "mmsi": "MMSI_Bench.parquet", "omnispatial": "data.json"}
#: What a problem of an image that does not exist adds, for a set whose image paths are
#: relative to somewhere other than its file's folder.
IMAGES_HINT = {
    "viewspatial": "ViewSpatial-Bench's image paths are relative to its repository root: give the repository "
    "folder as dataset.path (the set's file is then its eval/ViewSpatial-Bench.json), or that root as dataset.images",
}

#: Each set's official rule, the parser a choice pipeline on that format gets when it names none:
#: ViewSpatial-Bench's own ``evaluate.py``, MindCube's own evaluator (its ``extractors.py`` cascade
#: on the reply as written), and for 3DSRBench VLMEvalKit's exact matching, with which its authors
#: score it. lmms-eval's ports (``viewspatial``, ``mindcube``, ``3dsrbench-lmms``: after lmms-eval's
#: reasoning-tag strip) are alternatives a pipeline names, never defaults.
OFFICIAL_SET_PARSERS = {"viewspatial": "viewspatial-official", "mindcube": "mindcube-official", "3dsrbench": "vlmevalkit-exact",
                        "mmsi": "mmsi-official", "omnispatial": "omnispatial-re"}  # fmt: skip
#: Each set's own scorer: plain accuracy for ViewSpatial-Bench, MindCube's with its ``translation``
#: setting left out of the overall (a scorer option), and 3DSRBench's four accuracies per type
#: and sub-category (the authors' circular evaluation with VLMEvalKit's): what a pipeline on that
#: format gets first when it names no ``scorers:``.
OFFICIAL_SET_SCORERS = {"viewspatial": "choice", "mindcube": "choice-mindcube", "3dsrbench": "choice-3dsrbench", "mmsi": "choice", "omnispatial": "choice"}


#: The answer type every item of these sets asks for (its strategy and scorers are a pipeline's
#: defaults on such a set: :func:`povagent.config.plugin_checks.resolve_components`).
SET_ANSWER_TYPE = "choice"


def load_choice_set(file: str | Path, format: str, *, images: str | Path | None = None, cache_dir: str | Path | None = None) -> ChoiceSet:
    """The set in ``file``, read as ``format``, its image paths relative to (and confined to)
    the folder ``images`` (default: the file's folder); bad records are left out and named in
    ``problems``. ``file`` may be the set's repository folder where the set's image paths are
    relative to it (:data:`REPOSITORY_FILES`): the file is then found in it, and it is the
    default ``images``. :class:`~povagent.errors.DatasetError` when the file cannot be read at all."""
    file = Path(file)
    if format not in CHOICE_FORMATS:
        raise DatasetError(f"{file}: unknown dataset format {format!r} (known: {', '.join(CHOICE_FORMATS)})")
    if file.is_dir() and format in REPOSITORY_FILES:
        images = file if images is None else images
        file = file / REPOSITORY_FILES[format]
    if not file.is_file():
        raise DatasetError(f"{file}: not found (dataset.path of a {format} set names the set's file)")
    own_cache = cache_dir is None
    cache = Path(tempfile.mkdtemp(prefix="povagent-choices-")) if cache_dir is None else Path(cache_dir)
    items, problems = _read(file, format, cache)
    root = file.parent if images is None else Path(images)
    if not root.is_dir():
        raise DatasetError(f"{root}: not a folder (dataset.images names the folder a set's image paths are relative to)")
    from povagent.dataset.realworld import unknown_object

    instances = []
    lookups = ImageLookups(root)  # each image path resolved and checked once per set
    nowhere = unknown_object()  # the items' unknown observer and anchor: one object for the set
    for item in items:
        before = len(problems)
        frames = item_frames(root, item, str(file), _where(format, item.id), problems, cache, lookups)
        if frames is not None:
            instances.append(choice_instance(CHOICE_FORMATS[format], item, frames, nowhere))
        elif format in IMAGES_HINT and images is None and problems[before:] and problems[-1].message.endswith("does not exist"):
            problems[-1] = Problem(problems[-1].file, problems[-1].json_path, f"{problems[-1].message} ({IMAGES_HINT[format]})")
    choice_set = ChoiceSet(root, file, CHOICE_FORMATS[format], problems, instances, cache_dir=cache)
    if own_cache:
        weakref.finalize(choice_set, shutil.rmtree, str(cache), True)
    return choice_set


def validate_choice_set(file: str | Path, format: str, images: str | Path | None = None) -> list[Problem]:
    """Every problem of the set in ``file`` (``povagent validate F --format NAME``): the records
    its reader leaves out, each image fully decoded too; a file that cannot be read at all is
    one problem."""
    from povagent.dataset.image_files import decode_fully

    try:
        loaded = load_choice_set(file, format, images=images)
    except DatasetError as exc:
        return [Problem(str(file), "", str(exc).removeprefix(f"{file}: "))]
    problems = list(loaded.problems)
    for instance in loaded.instances():
        for frame in instance.frames:
            try:
                decode_fully(frame.file)
            except (OSError, ValueError) as exc:
                problems.append(Problem(str(file), f"{_where(format, instance.pair_id)}.images[{frame.index}]", f"image {frame.image_path!r} {exc}"))
    return problems


def _read(file: Path, format: str, cache: Path) -> tuple[list, list[Problem]]:
    from povagent.errors import ReadTargetError

    try:
        if format == "viewspatial":
            from povagent.dataset.choice_sets.viewspatial import read_viewspatial

            return read_viewspatial(file)
        if format == "mindcube":
            from povagent.dataset.choice_sets.mindcube import read_mindcube

            return read_mindcube(file)
        if format == "mmsi":
            from povagent.dataset.choice_sets.mmsi import read_mmsi

            return read_mmsi(file, cache)
        if format == "omnispatial":
            from povagent.dataset.choice_sets.omnispatial import read_omnispatial

            return read_omnispatial(file)
        from povagent.dataset.choice_sets.srbench3d import read_srbench3d

        return read_srbench3d(file, cache)
    except ReadTargetError as exc:
        raise DatasetError(str(exc)) from None
    except OSError as exc:
        raise DatasetError(f"{file}: cannot be read: {exc}") from None


def _where(format: str, item_id: str) -> str:
    """How a problem names a record: its position in a JSON list, or its id."""
    return f"$[{item_id}]" if format == "viewspatial" else f"record {item_id}"


__all__ = ["CHOICE_FORMATS", "OFFICIAL_SET_SCORERS", "SET_ANSWER_TYPE", "ChoiceSet", "load_choice_set", "validate_choice_set"]
