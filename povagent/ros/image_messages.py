"""``sensor_msgs/Image`` and ``CompressedImage`` to the RGB arrays the agent takes, and depth
images to metres.

Colour encodings read: ``rgb8``, ``bgr8``, ``rgba8``, ``bgra8`` (alpha dropped), ``mono8``
(grey to three equal channels). Compressed: ``jpeg`` and ``png`` (``format`` as image_transport
writes it, e.g. ``"rgb8; jpeg compressed bgr8"``; the codec is read from the bytes, never run
as anything but an image decoder). Depth: ``16UC1`` (millimetres, 0 = no reading) and ``32FC1``
(metres, NaN or 0 = no reading); holes become NaN.

Rows may be padded (``step`` larger than ``width`` x bytes per pixel): the padding is cut.
Every problem is an :class:`ImageProblem` whose ``kind`` names it (``encoding``,
``size``, ``compressed``, ``pixel_budget``), so a node can count each kind and log it once. Pure.

The pixel budget (:data:`MAX_PIXELS`) bounds the memory one image may take: a small compressed
message can claim a huge image (a 1.5 MB bag of twelve 6000 x 6000 PNGs decodes to gigabytes).
It is checked before any pixel is decoded: from ``width`` and ``height`` of a raw image, and
from the PNG or JPEG header of a compressed one (Pillow reads only the header until asked for
pixels); over it is the ``pixel_budget`` kind, never a decode.
"""

from __future__ import annotations

import io
from typing import Any

import numpy as np
from PIL import Image, UnidentifiedImageError

#: Channels and channel order of each colour encoding read (indices into the stored channels).
COLOUR_ENCODINGS: dict[str, tuple[int, tuple[int, ...]]] = {
    "rgb8": (3, (0, 1, 2)),
    "bgr8": (3, (2, 1, 0)),
    "rgba8": (4, (0, 1, 2)),
    "bgra8": (4, (2, 1, 0)),
    "mono8": (1, (0, 0, 0)),
}
#: Depth encodings read and the factor to metres.
DEPTH_ENCODINGS: dict[str, tuple[np.dtype, float]] = {
    "16UC1": (np.dtype(np.uint16), 0.001),
    "mono16": (np.dtype(np.uint16), 0.001),
    "32FC1": (np.dtype(np.float32), 1.0),
}
#: The pixel budget: the largest image decoded (width x height), 4096 x 3072 (12.6 megapixels,
#: above a robot camera's usual stream). One such RGB image is 38 MB; a full memory of
#: ``max_frames`` (30) keyframes at most 1.1 GB.
MAX_PIXELS = 4096 * 3072
#: The compressed formats read (Pillow is asked for no other decoder).
COMPRESSED_FORMATS = ("JPEG", "PNG")


class ImageProblem(ValueError):
    """An image message that cannot be read; ``kind`` is the counter it goes to."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


def _within_budget(width: int, height: int, what: str) -> None:
    if width * height > MAX_PIXELS:
        raise ImageProblem("pixel_budget", f"{what} of {width}x{height} pixels is over the pixel budget of {MAX_PIXELS:,}: not decoded")


def _raw_bytes(msg: Any) -> np.ndarray:
    # rclpy gives uint8[] as array.array or bytes, rosbags as a numpy array: all expose a buffer
    return np.frombuffer(memoryview(msg.data).cast("B"), dtype=np.uint8)


def _rows(msg: Any, bytes_per_pixel: int) -> np.ndarray:
    """The message's pixels as an ``(H, W * bytes_per_pixel)`` uint8 array, row padding cut."""
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    if height < 1 or width < 1:
        raise ImageProblem("size", f"image of size {width}x{height}")
    _within_budget(width, height, "image")
    row = width * bytes_per_pixel
    if step < row:
        raise ImageProblem("size", f"step {step} is shorter than a row of {width} pixels ({row} bytes)")
    data = _raw_bytes(msg)
    if data.size < step * height:
        raise ImageProblem("size", f"{data.size} bytes of data for {height} rows of {step} bytes")
    return data[: step * height].reshape(height, step)[:, :row]


def image_to_rgb(msg: Any) -> np.ndarray:
    """A ``sensor_msgs/Image`` as an ``(H, W, 3)`` uint8 RGB array."""
    encoding = str(msg.encoding).lower()
    if encoding not in COLOUR_ENCODINGS:
        raise ImageProblem("encoding", f"image encoding {msg.encoding!r} is not one of {', '.join(COLOUR_ENCODINGS)}")
    channels, order = COLOUR_ENCODINGS[encoding]
    pixels = _rows(msg, channels).reshape(int(msg.height), int(msg.width), channels)
    return np.ascontiguousarray(pixels[..., list(order)])


def compressed_to_rgb(msg: Any) -> np.ndarray:
    """A ``sensor_msgs/CompressedImage`` (JPEG or PNG) as an ``(H, W, 3)`` uint8 RGB array."""
    fmt = str(msg.format).lower()
    if "jpeg" not in fmt and "jpg" not in fmt and "png" not in fmt:
        raise ImageProblem("encoding", f"compressed image format {msg.format!r} is neither jpeg nor png")
    data = _raw_bytes(msg)
    if data.size == 0:
        raise ImageProblem("size", "compressed image with no data")
    try:
        # open reads the header only; the pixels are decoded by convert, after the budget check
        with Image.open(io.BytesIO(data.tobytes()), formats=COMPRESSED_FORMATS) as im:
            _within_budget(im.width, im.height, "compressed image")
            return np.asarray(im.convert("RGB"))
    except ImageProblem:
        raise
    except Image.DecompressionBombError as exc:  # Pillow's own guard, far above ours, met while reading the header
        raise ImageProblem("pixel_budget", f"compressed image over the pixel budget of {MAX_PIXELS:,}: {exc}; not decoded") from None
    except (UnidentifiedImageError, OSError, ValueError) as exc:
        raise ImageProblem("compressed", f"cannot decode the compressed image: {exc}") from None


def depth_to_metres(msg: Any) -> np.ndarray:
    """A depth ``sensor_msgs/Image`` as an ``(H, W)`` float array of metres, holes NaN."""
    encoding = str(msg.encoding)
    if encoding not in DEPTH_ENCODINGS:
        raise ImageProblem("encoding", f"depth encoding {encoding!r} is not one of {', '.join(DEPTH_ENCODINGS)}")
    dtype, scale = DEPTH_ENCODINGS[encoding]
    rows = _rows(msg, dtype.itemsize)
    big_endian = bool(getattr(msg, "is_bigendian", 0))
    values = np.ascontiguousarray(rows).view(dtype.newbyteorder(">" if big_endian else "<"))
    metres = values.reshape(int(msg.height), int(msg.width)).astype(float) * scale
    metres[~np.isfinite(metres) | (metres <= 0)] = np.nan
    return metres


__all__ = ["COLOUR_ENCODINGS", "COMPRESSED_FORMATS", "DEPTH_ENCODINGS", "MAX_PIXELS", "ImageProblem", "compressed_to_rgb", "depth_to_metres", "image_to_rgb"]
