"""A keyframe memory saved to a folder and loaded back: a robot's tour as a reproducible input.

Layout: ``memory.json`` (the settings and, per frame, its stamp, frame id, image file, 4x4
camera-to-map pose, pose convention, intrinsics and optional depth file), ``frame_NNNN.png``
(RGB) and ``depth_NNNN.npy`` (float metres). ``memory.json`` is written last, through a temporary
file and a rename, so a folder either holds a whole memory or none.

Saving treats the folder as untrusted too: it may be new, empty, or hold an earlier memory (a
``memory.json`` that reads as one), and any other folder is refused in one line before anything
is written, so a memory never lands among someone else's files. Every file is written through
:class:`~povagent.files.confined_write.ConfinedFolder` (aside, then renamed over its name): a link
planted in the folder is replaced, never written through.

Loading treats the folder as untrusted: file names must be plain names inside the folder (no
``/``, no ``..``), images are opened with Pillow's size guard, depth files with
``allow_pickle=False``, and every problem is one :class:`~povagent.errors.ConfigError` naming the
file and the field.
"""

from __future__ import annotations

import io
import json
import os
import re
from pathlib import Path
from typing import Literal

import numpy as np
from PIL import Image, UnidentifiedImageError
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from povagent.errors import ConfigError, ReadTargetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_inside
from povagent.files.confined_write import ConfinedFolder
from povagent.geometry.goals import PinholeCamera, PoseConvention
from povagent.ros.keyframes import Keyframe, KeyframeMemory, MemorySettings

MEMORY_FILE = "memory.json"
FORMAT_VERSION = 1
#: The largest ``memory.json`` read when deciding whether a folder holds an earlier memory
#: (30 frames take a few kilobytes; anything far larger is not ours).
MAX_MEMORY_JSON_BYTES = 16 * 1024 * 1024
#: The files a saved memory is made of (``memory.json.tmp``: one a killed save left behind).
_OURS = re.compile(r"^(frame_\d{4,}\.png|depth_\d{4,}\.npy|memory\.json(\.tmp)?)$")


class SavedFrame(BaseModel):
    """One frame of ``memory.json``."""

    model_config = ConfigDict(extra="forbid")
    stamp_ns: int
    frame_id: str = ""
    image: str = Field(pattern=r"^[A-Za-z0-9_.-]+\.png$")
    depth: str | None = Field(default=None, pattern=r"^[A-Za-z0-9_.-]+\.npy$")
    camera_to_map: list[list[float]] = Field(min_length=4, max_length=4)
    convention: Literal["opencv", "opengl", "ros"] = "opencv"
    fx: float
    fy: float
    cx: float
    cy: float
    width: int = Field(ge=1)
    height: int = Field(ge=1)


class SavedMemory(BaseModel):
    """``memory.json``: the format version, the rule settings and the frames in memory order."""

    model_config = ConfigDict(extra="forbid")
    format: Literal[1] = 1
    min_translation: float
    min_rotation: float
    max_frames: int
    coverage_depth: float
    grid: tuple[int, int]
    frames: list[SavedFrame]


def save_memory(memory: KeyframeMemory, folder: str | os.PathLike) -> Path:
    """Write ``memory`` to ``folder`` (created if needed); returns the ``memory.json`` path.

    ``folder`` must be new, empty or hold an earlier memory (:func:`check_memory_folder`); files
    of an earlier memory that the new one does not name are removed."""
    root = Path(folder)
    earlier = check_memory_folder(root)
    entries = []
    with ConfinedFolder(root) as out:
        for i, frame in enumerate(memory.frames):
            image = f"frame_{i:04d}.png"
            png = io.BytesIO()
            Image.fromarray(np.ascontiguousarray(frame.rgb, dtype=np.uint8)).save(png, format="PNG")
            out.write_replace(image, png.getvalue())
            depth = None
            if frame.depth is not None:
                depth = f"depth_{i:04d}.npy"
                npy = io.BytesIO()
                np.save(npy, np.asarray(frame.depth, dtype=np.float32), allow_pickle=False)
                out.write_replace(depth, npy.getvalue())
            cam = frame.camera
            entries.append(SavedFrame(
                stamp_ns=frame.stamp_ns, frame_id=frame.frame_id, image=image, depth=depth,
                camera_to_map=np.asarray(cam.camera_to_world).tolist(), convention=cam.convention.value,
                fx=cam.fx, fy=cam.fy, cx=cam.cx, cy=cam.cy, width=cam.width, height=cam.height,
            ))
        s = memory.settings
        saved = SavedMemory(min_translation=s.min_translation, min_rotation=s.min_rotation, max_frames=s.max_frames,
                            coverage_depth=s.coverage_depth, grid=s.grid, frames=entries)
        out.write_replace(MEMORY_FILE, json.dumps(saved.model_dump(mode="json"), indent=1), fsync=True)
        if earlier is not None:
            named = {f.image for f in entries} | {f.depth for f in entries if f.depth}
            for stale in ({f.image for f in earlier.frames} | {f.depth for f in earlier.frames if f.depth}) - named:
                out.unlink(stale)
    return root / MEMORY_FILE


def check_memory_folder(folder: str | os.PathLike) -> SavedMemory | None:
    """The earlier memory ``folder`` holds (``None`` when it is new or empty); :class:`ConfigError`
    in one line, before anything is written, when it holds anything else: the files of someone
    else are never written among. Reads nothing but a regular, bounded ``memory.json``."""
    root = Path(folder)
    if not root.is_dir():
        return None  # missing (made when saving) or not a folder (the confined writer names it)
    entries = sorted(p.name for p in root.iterdir())
    if not entries:
        return None
    earlier = _earlier_memory(root)
    if earlier is not None:
        return earlier
    shown = ", ".join(entries[:3]) + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")
    raise ConfigError(
        f"{root}: not empty and not a saved keyframe memory (it holds {shown}, and no readable {MEMORY_FILE}); "
        "nothing was written: choose another --save-memory folder, or empty this one"
    )


def _earlier_memory(root: Path) -> SavedMemory | None:
    """``root``'s ``memory.json`` when it is a plain file of ours and every entry beside it is a
    memory's file; ``None`` otherwise (a link, a FIFO, a huge file, other files, another format)."""
    if not all(_OURS.match(p.name) for p in root.iterdir()):
        return None
    try:
        return SavedMemory.model_validate_json(read_inside(root, MEMORY_FILE, MAX_MEMORY_JSON_BYTES, what="keyframe memory"))
    except (OSError, ReadTargetError, ValidationError):
        return None


def load_memory(folder: str | os.PathLike) -> KeyframeMemory:
    """The memory saved in ``folder``; :class:`ConfigError` naming the file and field when unusable."""
    root = Path(folder)
    path = root / MEMORY_FILE
    try:  # no link below the folder, regular files only, bounded: never waited on
        text = read_inside(root, MEMORY_FILE, MAX_MEMORY_JSON_BYTES, what="keyframe memory").decode("utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{path}: no saved keyframe memory here (write one with --save-memory)") from None
    except ReadTargetError as exc:
        raise ConfigError(str(exc)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from None
    try:
        saved = SavedMemory.model_validate_json(text)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"]) or "(top level)"
        raise ConfigError(f"{path}: field {field}: {first['msg']}") from None
    try:
        settings = MemorySettings(saved.min_translation, saved.min_rotation, saved.max_frames, saved.coverage_depth, saved.grid)
    except ValueError as exc:
        raise ConfigError(f"{path}: settings: {exc}") from None
    frames = [_load_frame(root, path, i, entry) for i, entry in enumerate(saved.frames)]
    memory = KeyframeMemory(settings)
    memory.restore(frames)
    return memory


def _load_frame(root: Path, path: Path, i: int, entry: SavedFrame) -> Keyframe:
    where = f"{path}: frames[{i}]"
    try:
        camera = PinholeCamera(np.asarray(entry.camera_to_map, dtype=float), entry.fx, entry.fy, entry.cx, entry.cy,
                               entry.width, entry.height, PoseConvention(entry.convention))
    except ValueError as exc:
        raise ConfigError(f"{where}.camera_to_map: {exc}") from None
    try:
        with Image.open(io.BytesIO(read_inside(root, entry.image, MAX_IMAGE_FILE_BYTES, what="keyframe image"))) as im:
            rgb = np.asarray(im.convert("RGB"))
    except ReadTargetError as exc:
        raise ConfigError(f"{where}.image: {exc}") from None
    except (OSError, UnidentifiedImageError, Image.DecompressionBombError) as exc:
        raise ConfigError(f"{where}.image: cannot read {entry.image}: {exc}") from None
    if rgb.shape[:2] != (entry.height, entry.width):
        raise ConfigError(f"{where}.image: {entry.image} is {rgb.shape[1]}x{rgb.shape[0]}, the camera says {entry.width}x{entry.height}")
    depth = None
    if entry.depth is not None:
        try:
            depth = np.load(io.BytesIO(read_inside(root, entry.depth, MAX_IMAGE_FILE_BYTES, what="keyframe depth")), allow_pickle=False)
        except ReadTargetError as exc:
            raise ConfigError(f"{where}.depth: {exc}") from None
        except (OSError, ValueError) as exc:
            raise ConfigError(f"{where}.depth: cannot read {entry.depth}: {exc}") from None
        if depth.ndim != 2 or not np.issubdtype(depth.dtype, np.floating):
            raise ConfigError(f"{where}.depth: {entry.depth} must be a 2D float array of metres")
        depth = depth.astype(float)
    return Keyframe(entry.stamp_ns, rgb, camera, depth, entry.frame_id)


__all__ = ["MAX_MEMORY_JSON_BYTES", "MEMORY_FILE", "SavedFrame", "SavedMemory", "check_memory_folder", "load_memory", "save_memory"]
