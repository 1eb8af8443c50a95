"""One robot frame as the model is shown it: named once from its content, letterboxed and
PNG-encoded only when a backend sends its pixels.

What it is for: a robot asks about the same keyframes command after command. A
:class:`ShownFrame` keeps what a ``locate`` call needs of a frame, made once per frame and not
once per call: the letterbox transform (:mod:`povagent.geometry.letterbox`), the name the image
store gives the letterboxed square and, the first time a backend asks for the image's bytes,
the square and its PNG encoding. The name is a digest of the frame's content (an array's or
image's pixels with its shape and type, or a file's bytes) and of how it is letterboxed: the
letterbox is a fixed function of these, so one name always stands for one square, and naming
a frame costs a hash, not a resize. An offline baseline that never looks at pixels
(``center``) never pays for a letterbox or an encode.

A frame handed in as a file that needs no letterbox (an RGB PNG or JPEG of the benchmark's
size) is passed through: the file itself is what the model is sent (:attr:`ShownFrame.file`),
read and checked by the image store, never decoded and encoded again.

The ROS keyframe memory keeps one per keyframe (:class:`~povagent.ros.keyframes.Keyframe`);
a robot app that asks about the same frames repeatedly may wrap them once and hand the wrapped
frames to :meth:`~povagent.agent.grounding_agent.GroundingAgent.locate`, and the agent itself
remembers the frames it was handed bare by their content (:mod:`povagent.agent.frame_memory`).
The pixels of a wrapped frame must not change after wrapping: the frame is named by the pixels
it had when it was first shown.

What it must not do: talk to a model or hold an image store: the store of a call refers to a
shown frame, the frame never refers to a store (a keyframe dropped from memory is freed).
"""

from __future__ import annotations

import hashlib
import os
import threading
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from povagent.agent.frame_inputs import FrameInput, array_image, checked_array, load_frame
from povagent.errors import BadInputError
from povagent.exchange.images import encode_png
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular
from povagent.geometry.letterbox import BENCHMARK_SIZE, DEFAULT_PAD_COLOR, Letterbox

#: Formats a file may be passed through in unchanged (what every backend accepts as is).
_PASS_THROUGH_FORMATS = frozenset({"PNG", "JPEG"})


class ShownFrame:
    """A frame made ready to be shown: named, letterboxed and encoded at most once each.

    Build it from anything :func:`~povagent.agent.frame_inputs.load_frame` takes (a path, a
    PIL image, an RGB array). Nothing is read or computed until a ``locate`` call needs it;
    every step is then done once and kept (thread-safe). ``pad_color`` is the letterbox's
    padding (the agent's own; an agent with another colour letterboxes the source afresh).
    """

    def __init__(self, frame: FrameInput, pad_color: tuple[int, int, int] = DEFAULT_PAD_COLOR) -> None:
        self.source = frame
        self.pad_color: tuple[int, int, int] = (int(pad_color[0]), int(pad_color[1]), int(pad_color[2]))
        self._lock = threading.Lock()
        self._box: Letterbox | None = None
        #: what the square is made from once checked: an array, or a decoded RGB image
        self._pixels: np.ndarray | Image.Image | None = None
        #: the digest of the frame's content (:func:`content_digest`)
        self._content: str | None = None
        self._file: Path | None = None
        self._png: bytes | None = None

    # -- what a call reads ----------------------------------------------------------------------
    def prepare(self, what: str, content: str | None = None) -> None:
        """Check the frame and name it, or decide to pass its file through (once); a frame
        that cannot be used is a :class:`~povagent.errors.BadInputError` naming ``what``.
        ``content``: the frame's :func:`content_digest`, when the caller has just taken it."""
        with self._lock:
            if self._box is not None:
                return
            source = self.source
            file = _pass_through_file(source, what)
            if file is not None:
                self._file, size = file
                self._box = Letterbox.for_size(*size)
                return
            pixels: np.ndarray | Image.Image
            if isinstance(source, np.ndarray):
                array = checked_array(source, what)
                pixels, size = array, (array.shape[1], array.shape[0])
            else:
                # an image is decoded now, so that a file that does not decode is refused now
                image = load_frame(source, what)
                pixels, size = image, image.size
            self._content = content or content_digest(pixels)
            self._pixels = pixels
            self._box = Letterbox.for_size(*size)

    @property
    def box(self) -> Letterbox:
        """The letterbox transform between the original frame and the square shown."""
        assert self._box is not None, "prepare() first"
        return self._box

    @property
    def file(self) -> Path | None:
        """The user's own file when it is passed through unchanged, else ``None``."""
        return self._file

    def image_hash(self) -> str:
        """The square's name in an image store: the SHA-256 of the frame's content digest and
        the letterbox (size, placement, padding) made of it; no letterbox, no encode."""
        assert self._content is not None, "prepare() first (and not a passed-through file)"
        box = self.box
        recipe = f"letterboxed {box.original} -> {box.resized} at {box.offset} in {box.size} padded {self.pad_color}\n"
        return hashlib.sha256(recipe.encode() + self._content.encode()).hexdigest()

    def png_bytes(self) -> bytes:
        """The square as PNG (letterboxed and encoded the first time it is asked for, then
        kept: the source's pixels are let go)."""
        with self._lock:
            if self._png is None:
                assert self._pixels is not None, "prepare() first (and not a passed-through file)"
                pixels = self._pixels
                image = array_image(pixels) if isinstance(pixels, np.ndarray) else pixels
                # as the image store encodes: the bytes sent before
                self._png = encode_png(self.box.apply(image, self.pad_color))
                self._pixels = None
            return self._png

    def for_pad(self, pad_color: tuple[int, int, int]) -> ShownFrame:
        """This frame, or a fresh one from its source when ``pad_color`` differs."""
        return self if tuple(pad_color) == self.pad_color else ShownFrame(self.source, pad_color)


def content_digest(frame: FrameInput) -> str:
    """What a frame is, as a SHA-256: an array's shape, type and bytes, an image's mode, size
    and pixels, or a file's bytes (read with the image-file bound). It costs a hash of the
    pixels, a small share of a letterbox (SHA-256 runs in hardware on current x86 and ARM
    CPUs, faster there than BLAKE2b); equal digests mean equal squares."""
    if isinstance(frame, np.ndarray):
        digest = hashlib.sha256(f"array {frame.dtype.str} {frame.shape}\n".encode())
        digest.update(np.ascontiguousarray(frame).data)
    elif isinstance(frame, Image.Image):
        digest = hashlib.sha256(f"image {frame.mode} {frame.size}\n".encode())
        digest.update(frame.tobytes())
    else:
        digest = hashlib.sha256(b"file\n")
        digest.update(read_regular(os.fspath(frame), MAX_IMAGE_FILE_BYTES, what="image file"))
    return digest.hexdigest()


def _pass_through_file(frame: FrameInput, what: str) -> tuple[Path, tuple[int, int]] | None:
    """``(path, size)`` when ``frame`` is a file the model can be sent as it is: an RGB PNG or
    JPEG of the benchmark's size. Only the header is read; the image store checks the bytes."""
    if not isinstance(frame, (str, os.PathLike)):
        return None
    path = Path(frame)
    try:
        with Image.open(path) as im:
            usable = im.format in _PASS_THROUGH_FORMATS and im.mode == "RGB" and im.size == (BENCHMARK_SIZE, BENCHMARK_SIZE)
            size = im.size
    except FileNotFoundError:
        raise BadInputError(f"{what}: no such image file: {path}") from None
    except (UnidentifiedImageError, Image.DecompressionBombError, OSError, ValueError) as exc:
        raise BadInputError(f"{what}: cannot read image {path}: {exc}") from None
    return (path, size) if usable else None


__all__ = ["ShownFrame"]
