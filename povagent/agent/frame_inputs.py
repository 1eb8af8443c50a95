"""What a robot app hands the agent, checked: frames as files, PIL images or arrays, and the
cameras and depth images that line up with them.

What it is for: turning each frame into an RGB PIL image (:func:`load_frame`) and a per-image
argument (``cameras``, ``depths``) into one entry per image shown (:func:`aligned`). Every
problem is a :class:`~povagent.errors.BadInputError` that names the argument (``frames[2]``,
``cameras``) and says what was expected. What it must not do: letterbox, store or send images
(:mod:`povagent.agent.prepared_call`), or guess a frame's channel order (arrays are RGB).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, UnidentifiedImageError

from povagent.errors import BadInputError

#: What a frame may be: a path, a PIL image, or an ``(H, W)``/``(H, W, 3|4)`` RGB(A) array.
FrameInput = str | os.PathLike | Image.Image | np.ndarray


def load_frame(frame: FrameInput, what: str) -> Image.Image:
    """A frame as an RGB PIL image; :class:`BadInputError` naming ``what`` when unusable.

    Arrays are taken as RGB (OpenCV's BGR arrays must be converted first): ``uint8``, or floats
    on ``[0, 1]``; 2D arrays are grey, a 4th channel (alpha) is dropped.
    """
    if isinstance(frame, Image.Image):
        return frame.convert("RGB")
    if isinstance(frame, np.ndarray):
        return _array_to_image(frame, what)
    if isinstance(frame, (str, os.PathLike)):
        path = Path(frame)
        try:
            with Image.open(path) as im:
                im.load()
                return im.convert("RGB")
        except FileNotFoundError:
            raise BadInputError(f"{what}: no such image file: {path}") from None
        except (UnidentifiedImageError, Image.DecompressionBombError, OSError, ValueError) as exc:
            raise BadInputError(f"{what}: cannot read image {path}: {exc}") from None
    raise BadInputError(f"{what}: expected a path, a PIL image or a numpy array, got {type(frame).__name__}")


def _array_to_image(a: np.ndarray, what: str) -> Image.Image:
    return array_image(checked_array(a, what))


def checked_array(a: np.ndarray, what: str) -> np.ndarray:
    """``a`` if it is a usable image array (an ``(H, W, 1)`` array as ``(H, W)``), else a
    :class:`BadInputError` naming ``what``; nothing is converted (:func:`array_image` does)."""
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))):
        raise BadInputError(f"{what}: an image array must be (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}")
    if a.shape[0] < 1 or a.shape[1] < 1:
        raise BadInputError(f"{what}: empty image array of shape {a.shape}")
    if a.dtype == np.uint8 or a.dtype == np.bool_:
        return a
    if np.issubdtype(a.dtype, np.floating):
        if not np.isfinite(a).all() or a.min() < 0 or a.max() > 1:
            raise BadInputError(f"{what}: a float image array must hold values in [0, 1]")
        return a
    raise BadInputError(f"{what}: image arrays must be uint8 or float in [0, 1], got dtype {a.dtype}")


def array_image(a: np.ndarray) -> Image.Image:
    """The RGB image of an array :func:`checked_array` accepted."""
    if a.dtype == np.uint8:
        data = a
    elif a.dtype == np.bool_:
        data = a.astype(np.uint8) * 255
    else:
        data = np.round(a * 255).astype(np.uint8)
    if data.ndim == 3 and data.shape[2] == 4:
        data = data[..., :3]
    return Image.fromarray(np.ascontiguousarray(data)).convert("RGB")


def aligned(values: Any, n: int, name: str, types: tuple[type, ...]) -> list[Any]:
    """``values`` as a list of ``n`` entries (``None`` -> all ``None``; one bare value for one image)."""
    if values is None:
        return [None] * n
    if isinstance(values, types):
        values = [values]
    values = list(values)
    if len(values) != n:
        raise BadInputError(f"{name}: got {len(values)} entries for {n} image(s); give one per image shown (None allowed)")
    for i, v in enumerate(values):
        if v is not None and not isinstance(v, types):
            expected = " or ".join(t.__name__ for t in types)
            raise BadInputError(f"{name}[{i}]: expected {expected} or None, got {type(v).__name__}")
    return values
