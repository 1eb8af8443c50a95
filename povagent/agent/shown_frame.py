"""One robot frame as the model is shown it: letterboxed once, named once, PNG-encoded only
when a backend sends its pixels.

What it is for: a robot asks about the same keyframes command after command. A
:class:`ShownFrame` keeps what a ``locate`` call needs of a frame, made once per frame and not
once per call: the letterbox transform (:mod:`povagent.geometry.letterbox`), the letterboxed
square, the name the image store gives it (the SHA-256 of the square's pixels, so naming it
never encodes it) and, the first time a backend asks for the image's bytes, its PNG encoding.
An offline baseline that never looks at pixels (``center``) never pays for an encode.

A frame handed in as a file that needs no letterbox (an RGB PNG or JPEG of the benchmark's
size) is passed through: the file itself is what the model is sent (:attr:`ShownFrame.file`),
read and checked by the image store, never decoded and encoded again.

The ROS keyframe memory keeps one per keyframe (:class:`~povagent.ros.keyframes.Keyframe`);
a robot app that asks about the same frames repeatedly wraps them once and hands the wrapped
frames to :meth:`~povagent.agent.grounding_agent.GroundingAgent.locate`. The pixels must not
change after wrapping: the frame is named by the pixels it had when it was first shown.

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

from povagent.agent.frame_inputs import FrameInput, load_frame
from povagent.errors import BadInputError
from povagent.exchange.images import encode_png
from povagent.geometry.letterbox import BENCHMARK_SIZE, DEFAULT_PAD_COLOR, Letterbox

#: Formats a file may be passed through in unchanged (what every backend accepts as is).
_PASS_THROUGH_FORMATS = frozenset({"PNG", "JPEG"})


class ShownFrame:
    """A frame made ready to be shown: letterboxed, named and encoded at most once each.

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
        self._square: Image.Image | None = None
        self._file: Path | None = None
        self._hash: str | None = None
        self._png: bytes | None = None

    # -- what a call reads ----------------------------------------------------------------------
    def prepare(self, what: str) -> None:
        """Load and letterbox the frame, or decide to pass its file through (once); a frame
        that cannot be used is a :class:`~povagent.errors.BadInputError` naming ``what``."""
        with self._lock:
            if self._box is not None:
                return
            file = _pass_through_file(self.source, what)
            if file is not None:
                self._file, size = file
                self._box = Letterbox.for_size(*size)
                return
            image = load_frame(self.source, what)
            box = Letterbox.for_size(image.size[0], image.size[1])
            self._square = box.apply(image, self.pad_color)
            self._box = box

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
        """The square's name in an image store: the SHA-256 of its size and RGB pixels
        (computed once; no encode)."""
        with self._lock:
            if self._hash is None:
                assert self._square is not None, "prepare() first (and not a passed-through file)"
                pixels = np.asarray(self._square)
                digest = hashlib.sha256(f"rgb {self._square.size[0]}x{self._square.size[1]}\n".encode())
                digest.update(np.ascontiguousarray(pixels).data)
                self._hash = digest.hexdigest()
            return self._hash

    def png_bytes(self) -> bytes:
        """The square as PNG (encoded the first time it is asked for, then kept: the square's
        pixels are let go)."""
        with self._lock:
            if self._png is None:
                assert self._square is not None, "prepare() first (and not a passed-through file)"
                self._png = encode_png(self._square)  # as the image store encodes: the bytes sent before
                self._square = None if self._hash is not None else self._square
            return self._png

    def for_pad(self, pad_color: tuple[int, int, int]) -> ShownFrame:
        """This frame, or a fresh one from its source when ``pad_color`` differs."""
        return self if tuple(pad_color) == self.pad_color else ShownFrame(self.source, pad_color)


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
