"""A VSI-Bench file and its scene videos loaded into runnable instances.

``load_vsibench(file, frames=N)`` reads the records (:mod:`.vsibench`), and for each scene
video they name (``<dataset>/<scene_name>.mp4``, confined to the folder ``videos``, by default
the file's own: an absolute path, a ``..`` or a symlink leading out is a problem and never
opened) samples ``N`` frames as VSI-Bench's models sample them
(:func:`povagent.dataset.video_frames.sample_frames`), once per scene, into the set's cache
folder. Each record becomes an :class:`~povagent.dataset.instances.Instance` showing those
frames: a multiple-choice one (``question``) or a numerical one (``numeric``), no direction, no
condition, NaN 3D fields. A record whose video is missing or cannot be decoded is left out and
named in one problem line (file, record, field).
"""

from __future__ import annotations

import shutil
import tempfile
import weakref
from pathlib import Path

from PIL import Image

from povagent.dataset.choice_sets.external import ChoiceSet, image_camera, question_instance
from povagent.dataset.choice_sets.vsibench_records import SceneQuestion, read_vsibench
from povagent.dataset.frame_cache import FrameCache, cached_sample_frames
from povagent.dataset.instances import Frame, Instance
from povagent.dataset.paths import OutsideDatasetError, confined, dataset_root, shown
from povagent.dataset.problems import Problem
from povagent.dataset.release_models import SceneObject
from povagent.dataset.video_frames import VideoError, sample_indices
from povagent.errors import DatasetError, PovagentError, ReadTargetError

#: The set's name: the instances' "house" (ids are ``vsibench/<record id>``).
SET_NAME = "vsibench"
#: The frames an item shows unless ``frames:`` says otherwise (the set's 32-frame models).
DEFAULT_FRAMES = 32


def load_vsibench(
    file: str | Path,
    frames: int = DEFAULT_FRAMES,
    *,
    videos: str | Path | None = None,
    cache_dir: str | Path | None = None,
    decode: bool = True,
    frame_cache: str | Path | None = None,
) -> ChoiceSet:
    """The set in ``file`` (``.parquet`` or ``.jsonl``), each item showing ``frames`` frames of
    its scene's video found under ``videos`` (default: the file's folder); bad records are left
    out and named in ``problems``. :class:`~povagent.errors.DatasetError` when the file cannot
    be read at all. ``decode=False`` reads the questions and their gold answers (what rescoring
    and the report need) without sampling the videos: each frame is the path a decoded frame
    would have, and only a scene's first frame (always sampled) is written, where its video is
    there and decodes (the report's card shows it); a missing video is then no problem.
    ``frame_cache``: a folder keeping each video's sampled frames across runs
    (:mod:`povagent.dataset.frame_cache`; default: none, every video decoded)."""
    file = Path(file)
    if not file.is_file():
        raise DatasetError(f"{file}: not found (dataset.path of a vsibench set names its .parquet or .jsonl file)")
    root = file.parent if videos is None else Path(videos)
    if not root.is_dir():
        raise DatasetError(f"{root}: not a folder (dataset.images names the folder holding the videos, <dataset>/<scene_name>.mp4)")
    try:
        items, problems = read_vsibench(file)
    except ReadTargetError as exc:
        raise DatasetError(str(exc)) from None
    except OSError as exc:
        raise DatasetError(f"{file}: cannot be read: {exc}") from None
    own_cache = cache_dir is None
    cache = Path(tempfile.mkdtemp(prefix="povagent-vsibench-")) if cache_dir is None else Path(cache_dir)
    from povagent.dataset.realworld_set import unknown_object

    nowhere = unknown_object()
    real_root = dataset_root(root)
    kept = FrameCache(Path(frame_cache)) if frame_cache is not None else None
    scenes: dict[str, tuple[Frame, ...] | str] = {}
    instances = []
    for item in items:
        shown_frames = scenes.get(item.video)
        if shown_frames is None:
            shown_frames = scenes[item.video] = (
                _scene_frames(real_root, root, item.video, frames, cache, kept)
                if decode
                else _first_frame_only(real_root, root, item.video, frames, cache, kept)
            )
        if isinstance(shown_frames, str):
            problems.append(Problem(str(file), f"record {item.id}.scene_name", shown_frames))
            continue
        instances.append(scene_instance(item, shown_frames, nowhere))
    loaded = ChoiceSet(root, file, SET_NAME, problems, instances, cache_dir=cache)
    if own_cache:
        weakref.finalize(loaded, shutil.rmtree, str(cache), True)
    return loaded


def _scene_frames(real_root: Path, root: Path, video: str, n: int, cache: Path, kept: FrameCache | None = None) -> tuple[Frame, ...] | str:
    """The ``n`` sampled frames of ``video`` (relative to ``root``), or why there are none."""
    try:
        path = confined(real_root, root, video, what="video path")
    except OutsideDatasetError as exc:
        return str(exc)
    if not path.is_file():
        return f"video {shown(video)} does not exist"
    try:
        files = cached_sample_frames(path, n, cache / video, kept)  # dataset and scene_name are plain names: a folder per video
    except (VideoError, ReadTargetError) as exc:
        return f"video {shown(video)}: {exc}"
    with Image.open(files[0]) as first:
        camera = image_camera(*first.size)
    return tuple(Frame(k, f"{video}#{k}", f, camera) for k, f in enumerate(files))


def _first_frame_only(real_root: Path, root: Path, video: str, n: int, cache: Path, kept: FrameCache | None = None) -> tuple[Frame, ...]:
    """Where the ``n`` frames of ``video`` would be written, only the first of them written (a
    video that is missing, outside the folder or undecodable, or no PyAV: none written)."""
    folder = cache / video
    try:
        cached_sample_frames(confined(real_root, root, video, what="video path"), 1, folder, kept)  # linspace(0, total - 1, 1): frame 0
    except (OutsideDatasetError, VideoError, PovagentError, OSError):
        pass  # the gold answers are all that is needed: the card goes without its image
    camera = image_camera(1, 1)
    return tuple(Frame(k, f"{video}#{k}", folder / f"frame-{k:03d}.png", camera) for k in range(n))


def scene_instance(item: SceneQuestion, frames: tuple[Frame, ...], nowhere: SceneObject | None = None) -> Instance:
    """The runnable instance of one record: id ``vsibench/<record id>``, showing ``frames``.
    ``nowhere``: the unknown object to stand for its observer and anchor (one a set may share)."""
    return question_instance(SET_NAME, item.id, item.question, frames, nowhere)


def validate_vsibench(file: str | Path, frames: int = DEFAULT_FRAMES, videos: str | Path | None = None, frame_cache: str | Path | None = None) -> list[Problem]:
    """Every problem of the set in ``file``: the records left out (each video decoded once, or
    its frames taken from ``frame_cache``); a file that cannot be read at all is one problem."""
    try:
        return list(load_vsibench(file, frames, videos=videos, frame_cache=frame_cache).problems)
    except DatasetError as exc:
        return [Problem(str(file), "", str(exc).removeprefix(f"{file}: "))]


__all__ = ["DEFAULT_FRAMES", "SET_NAME", "load_vsibench", "sample_indices", "scene_instance", "validate_vsibench"]
