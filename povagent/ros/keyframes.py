"""The keyframe memory: which of a robot's frames the agent is shown.

The rules (each pinned by a test in ``tests/ros/test_keyframes.py``):

* **Keep on motion.** A frame is kept when its camera moved more than ``min_translation``
  metres (default 0.5) or turned more than ``min_rotation`` degrees (default 30) since the last
  frame *accepted*; the first frame is always kept. "Accepted" counts a frame even if the
  eviction below drops it at once, so a robot standing still is not offered the same view
  again and again.
* **Drop the most covered view when full.** With more than ``max_frames`` (default 30), the frame
  whose view is most covered by the others is dropped. A frame's coverage is the share of its
  sample points (a ``grid`` of pixel centres, 8 x 6 by default, each taken to its depth image's
  reading or, without one, ``coverage_depth`` metres along its ray, default 2 m) that fall inside
  the image of at least one other kept frame, in front of it (occlusion is not modelled). The
  highest coverage is dropped; a tie drops the oldest. The new frame takes part: when it is the
  most covered, it is the one dropped.

Frames are kept in the order they were accepted; the agent sees them in that order, so a frame
index in an answer is an index into :attr:`KeyframeMemory.frames`. The memory is saved to and
loaded from a folder (:mod:`povagent.ros.memory_folder`). Pure: no clock, no ROS.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from povagent.agent.shown_frame import ShownFrame
from povagent.geometry.goals import PinholeCamera
from povagent.ros.transforms import rotation_angle

DEFAULT_MIN_TRANSLATION = 0.5
DEFAULT_MIN_ROTATION = 30.0
DEFAULT_MAX_FRAMES = 30
DEFAULT_COVERAGE_DEPTH = 2.0
DEFAULT_GRID = (8, 6)


@dataclass(frozen=True)
class Keyframe:
    """One kept frame: its stamp (ns), RGB pixels, camera (pose in the map + intrinsics), optional depth (m).

    ``shown`` is the frame as the agent shows it (letterboxed, named and encoded once, on the
    first command that needs each), kept with the keyframe so that every later command over it
    reuses that work (:mod:`povagent.agent.shown_frame`)."""

    stamp_ns: int
    rgb: np.ndarray
    camera: PinholeCamera
    depth: np.ndarray | None = None
    frame_id: str = ""
    shown: ShownFrame = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "shown", ShownFrame(self.rgb))

    def optical_rotation(self) -> np.ndarray:
        """The camera's optical axes (rows right, down, forward) in the map: comparable across conventions."""
        return self.camera.optical_axes()


@dataclass(frozen=True)
class MemorySettings:
    """The memory's rule parameters."""

    min_translation: float = DEFAULT_MIN_TRANSLATION
    min_rotation: float = DEFAULT_MIN_ROTATION
    max_frames: int = DEFAULT_MAX_FRAMES
    coverage_depth: float = DEFAULT_COVERAGE_DEPTH
    grid: tuple[int, int] = DEFAULT_GRID

    def __post_init__(self) -> None:
        if not (self.min_translation >= 0 and self.min_rotation >= 0):
            raise ValueError("min_translation and min_rotation must be >= 0")
        if self.max_frames < 1:
            raise ValueError(f"max_frames must be at least 1, got {self.max_frames}")
        if not self.coverage_depth > 0:
            raise ValueError(f"coverage_depth must be positive (metres), got {self.coverage_depth}")
        if len(self.grid) != 2 or min(self.grid) < 1:
            raise ValueError(f"grid must be two positive counts (columns, rows), got {self.grid}")


class KeyframeMemory:
    """Frames kept by the motion rule, bounded by the coverage rule (see the module docstring)."""

    def __init__(self, settings: MemorySettings | None = None) -> None:
        self.settings = settings or MemorySettings()
        self.frames: list[Keyframe] = []
        self._last_accepted: Keyframe | None = None

    def moved_enough(self, candidate: Keyframe) -> bool:
        """Whether ``candidate`` moved or turned past the thresholds since the last accepted frame."""
        last = self._last_accepted
        if last is None:
            return True
        moved = float(np.linalg.norm(candidate.camera.position - last.camera.position))
        turned = rotation_angle(last.optical_rotation(), candidate.optical_rotation())
        return moved > self.settings.min_translation or turned > self.settings.min_rotation

    def offer(self, candidate: Keyframe) -> Keyframe | None:
        """Offer a frame; returns the frame dropped to make room (possibly ``candidate``), else None.

        ``candidate in memory.frames`` tells whether it was kept."""
        if not self.moved_enough(candidate):
            return None
        self._last_accepted = candidate
        self.frames.append(candidate)
        if len(self.frames) <= self.settings.max_frames:
            return None
        scores = coverage(self.frames, self.settings)
        drop = int(np.argmax(scores))  # argmax takes the first of equals: the oldest
        return self.frames.pop(drop)

    def restore(self, frames: list[Keyframe]) -> None:
        """Replace the memory's frames (a loaded folder); the newest becomes the last accepted."""
        self.frames = list(frames)
        self._last_accepted = self.frames[-1] if self.frames else None

    def __len__(self) -> int:
        return len(self.frames)


def sample_points(frame: Keyframe, settings: MemorySettings) -> np.ndarray:
    """The frame's coverage samples in the map: grid pixel centres at their depth (``(N, 3)``)."""
    cam = frame.camera
    cols, rows = settings.grid
    us = (np.arange(cols) + 0.5) * cam.width / cols
    vs = (np.arange(rows) + 0.5) * cam.height / rows
    pixels = np.stack(np.meshgrid(us, vs), axis=-1).reshape(-1, 2)
    depth = np.full(len(pixels), settings.coverage_depth)
    if frame.depth is not None and frame.depth.ndim == 2 and frame.depth.size:
        h, w = frame.depth.shape
        cols_i = np.clip((pixels[:, 0] / cam.width * w).astype(int), 0, w - 1)
        rows_i = np.clip((pixels[:, 1] / cam.height * h).astype(int), 0, h - 1)
        measured = frame.depth[rows_i, cols_i]
        depth = np.where(np.isfinite(measured) & (measured > 0), measured, depth)
    return cam.point_at_depth(pixels, depth)


def seen_by(camera: PinholeCamera, points: np.ndarray) -> np.ndarray:
    """Which map points fall inside ``camera``'s image, in front of it."""
    pixels = camera.project_pixels(points)
    with np.errstate(invalid="ignore"):
        return (
            np.isfinite(pixels).all(axis=-1)
            & (pixels[:, 0] >= 0) & (pixels[:, 0] <= camera.width)
            & (pixels[:, 1] >= 0) & (pixels[:, 1] <= camera.height)
        )


def coverage(frames: list[Keyframe], settings: MemorySettings) -> np.ndarray:
    """Each frame's coverage: the share of its samples seen by at least one other frame."""
    out = np.zeros(len(frames))
    for i, frame in enumerate(frames):
        points = sample_points(frame, settings)
        covered = np.zeros(len(points), dtype=bool)
        for j, other in enumerate(frames):
            if j != i:
                covered |= seen_by(other.camera, points)
        out[i] = covered.mean()
    return out


__all__ = [
    "DEFAULT_COVERAGE_DEPTH",
    "DEFAULT_GRID",
    "DEFAULT_MAX_FRAMES",
    "DEFAULT_MIN_ROTATION",
    "DEFAULT_MIN_TRANSLATION",
    "Keyframe",
    "KeyframeMemory",
    "MemorySettings",
    "coverage",
    "sample_points",
    "seen_by",
]
