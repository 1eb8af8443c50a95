"""Letterboxing real-world frames to the benchmark's square size, and mapping answers back.

POVBench frames are 512x512; the paper resizes its real house-tour frames "to 512 x 512 using
letterbox padding". A frame of any aspect ratio is scaled by ``s = 512 / max(w, h)`` to
``(round(w s), round(h s))`` and pasted centred (integer offsets, the remainder of an odd
padding going right/bottom) on a padded square. The model answers in the square; the answer
is mapped back to the original frame through the exact transform kept here.

Coordinate convention (the one :mod:`povagent.geometry.camera` and the official metric use):
coordinates are continuous, with ``(0, 0)`` the top-left corner of the top-left pixel and
``(W, H)`` the bottom-right corner of the bottom-right pixel; pixel ``(i, j)`` covers
``[i, i+1) x [j, j+1)`` and its centre is ``(i + 0.5, j + 0.5)``. Pillow's resize samples on
the same convention (output pixel centre ``k + 0.5`` reads input ``(k + 0.5) w / rw``), so
the transform below is exactly the one the pixels went through: per axis
``X = offset + x * (resized / original)``. Per-axis scales are kept (rounding makes them
differ from ``s`` by less than half a pixel's worth) so the round trip is exact.

Pure: no files, no model. Images in, images out; numbers in, numbers out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from PIL import Image

#: The side of POVBench frames.
BENCHMARK_SIZE = 512

#: Letterbox padding colour (black, as video letterboxing is).
DEFAULT_PAD_COLOR: tuple[int, int, int] = (0, 0, 0)


@dataclass(frozen=True)
class Letterbox:
    """The exact transform between an original frame and its letterboxed square.

    ``original`` and ``resized`` are ``(width, height)``; ``offset`` is where the resized image
    sits in the ``size`` x ``size`` square (integer pixels).
    """

    original: tuple[int, int]
    resized: tuple[int, int]
    offset: tuple[int, int]
    size: int = BENCHMARK_SIZE

    @classmethod
    def for_size(cls, width: int, height: int, size: int = BENCHMARK_SIZE) -> Letterbox:
        """The letterbox of a ``width`` x ``height`` frame into a ``size`` square."""
        if width < 1 or height < 1:
            raise ValueError(f"frame size must be positive, got {width}x{height}")
        s = size / max(width, height)
        # round() and not int(): 1000x563 -> 512x288.3 must become 288, not be truncated;
        # max(1, ...) keeps a 1-pixel-high strip visible after downscaling
        rw = min(size, max(1, round(width * s)))
        rh = min(size, max(1, round(height * s)))
        return cls((int(width), int(height)), (rw, rh), ((size - rw) // 2, (size - rh) // 2), size)

    # -- the transform ------------------------------------------------------------------------
    @property
    def scale(self) -> tuple[float, float]:
        """Per-axis scale original -> square (``resized / original``)."""
        return (self.resized[0] / self.original[0], self.resized[1] / self.original[1])

    @property
    def is_identity(self) -> bool:
        """True when the frame is already the square size (no resize, no padding)."""
        return self.original == (self.size, self.size)

    def to_square(self, points: Sequence[float] | np.ndarray) -> np.ndarray:
        """Original-frame coordinates ``(..., 2)`` to letterboxed-square coordinates."""
        p = np.asarray(points, dtype=float)
        sx, sy = self.scale
        return np.stack([self.offset[0] + p[..., 0] * sx, self.offset[1] + p[..., 1] * sy], axis=-1)

    def to_original(self, points: Sequence[float] | np.ndarray, *, clamp: bool = True) -> np.ndarray:
        """Letterboxed-square coordinates ``(..., 2)`` back to the original frame.

        With ``clamp`` (the default) a point on the padding is moved to the nearest edge of the
        original frame, ``[0, W] x [0, H]``: a model pointing at the black border meant the
        nearest image content, and a robot must never get a pixel outside its frame.
        """
        p = np.asarray(points, dtype=float)
        sx, sy = self.scale
        x = (p[..., 0] - self.offset[0]) / sx
        y = (p[..., 1] - self.offset[1]) / sy
        if clamp:
            x = np.clip(x, 0.0, float(self.original[0]))
            y = np.clip(y, 0.0, float(self.original[1]))
        return np.stack([x, y], axis=-1)

    def content_box(self) -> tuple[int, int, int, int]:
        """``(left, top, right, bottom)`` of the image content inside the square (exclusive right/bottom)."""
        ox, oy = self.offset
        return (ox, oy, ox + self.resized[0], oy + self.resized[1])

    def on_padding(self, point: Sequence[float]) -> bool:
        """True when a square coordinate lies outside the image content (on the padding)."""
        left, top, right, bottom = self.content_box()
        return not (left <= point[0] <= right and top <= point[1] <= bottom)

    # -- images -------------------------------------------------------------------------------
    def apply(self, image: Image.Image, pad_color: tuple[int, int, int] = DEFAULT_PAD_COLOR) -> Image.Image:
        """The letterboxed RGB square of ``image`` (which must have the ``original`` size)."""
        if image.size != self.original:
            raise ValueError(f"image is {image.size[0]}x{image.size[1]}, the letterbox was made for "
                             f"{self.original[0]}x{self.original[1]}")
        rgb = image.convert("RGB")
        if self.is_identity:
            return rgb
        resized = rgb if rgb.size == self.resized else rgb.resize(self.resized, Image.Resampling.BICUBIC)
        square = Image.new("RGB", (self.size, self.size), pad_color)
        square.paste(resized, self.offset)
        return square


def letterbox(image: Image.Image, size: int = BENCHMARK_SIZE,
              pad_color: tuple[int, int, int] = DEFAULT_PAD_COLOR) -> tuple[Image.Image, Letterbox]:
    """Letterbox ``image`` into a ``size`` square; returns the square and its transform."""
    box = Letterbox.for_size(image.size[0], image.size[1], size)
    return box.apply(image, pad_color), box


def pixel_index(point: Sequence[float], width: int, height: int) -> tuple[int, int]:
    """The ``(column, row)`` of the pixel containing a continuous coordinate, clamped to the frame.

    ``x = W`` (the right edge, a valid continuous coordinate) falls in column ``W - 1``.
    """
    col = int(np.clip(np.floor(point[0]), 0, width - 1))
    row = int(np.clip(np.floor(point[1]), 0, height - 1))
    return (col, row)
