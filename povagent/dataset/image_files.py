"""Is an image file sound: complete, uncorrupted, and of the size its camera says?

Checked when a dataset loads, once per file per process (the verdict is kept under the file's
path, size and modification time, so a file changed since is checked again), never on the
request path. A PNG, the release's format, is checked without decoding pixels: every chunk must
be complete with a matching checksum, the header must come first and give the size, and the
end marker must be there; a truncated file or a flipped byte fails in a fraction of a
millisecond. Other formats are decoded once. ``povagent validate`` decodes every image fully on
top of this.

This module reads image files and judges them; it never decides what a failure costs (the
loader drops a pair or a house, the image store raises).
"""

from __future__ import annotations

import io
import os
import threading
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path

from PIL import Image, UnidentifiedImageError

from povagent.dataset.paths import shown
from povagent.errors import ReadTargetError
from povagent.files.confined_read import MAX_IMAGE_FILE_BYTES, read_regular

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: Larger images are refused before anything decodes them (Pillow's own bomb limit).
MAX_PIXELS = Image.MAX_IMAGE_PIXELS or 89_478_485
#: Verdicts kept per process; more distinct files than this and the memory is cleared.
_MAX_REMEMBERED = 200_000


class ImageFileError(ValueError):
    """An image file is unusable; the message is a sentence without the file name."""


@dataclass(frozen=True)
class ImageFacts:
    """What a sound image file is: its pixel size and media type."""

    width: int
    height: int
    media_type: str

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)``."""
        return (self.width, self.height)


def check_image_bytes(data: bytes) -> ImageFacts:
    """The facts of an encoded image, or :class:`ImageFileError` saying what is wrong with it."""
    if data.startswith(PNG_SIGNATURE):
        return _check_png(memoryview(data))
    return _decode_other(data)


def _check_png(data: memoryview) -> ImageFacts:
    n, pos = len(data), len(PNG_SIGNATURE)
    width = height = 0
    saw_data = False
    while True:
        if pos + 12 > n:
            raise ImageFileError("cannot be decoded: truncated (the file ends before the PNG's end marker)")
        length = int.from_bytes(data[pos : pos + 4], "big")
        kind = bytes(data[pos + 4 : pos + 8])
        end = pos + 12 + length
        if end > n:
            raise ImageFileError(f"cannot be decoded: truncated (the file ends inside its {_chunk(kind)} chunk)")
        if zlib.crc32(data[pos + 4 : pos + 8 + length]) != int.from_bytes(data[pos + 8 + length : end], "big"):
            raise ImageFileError(f"cannot be decoded: corrupt (its {_chunk(kind)} chunk fails its checksum)")
        if pos == len(PNG_SIGNATURE):
            if kind != b"IHDR" or length != 13:
                raise ImageFileError("cannot be decoded: corrupt (a PNG must start with its IHDR header)")
            width = int.from_bytes(data[pos + 8 : pos + 12], "big")
            height = int.from_bytes(data[pos + 12 : pos + 16], "big")
            _check_pixels(width, height)
        elif kind == b"IDAT":
            saw_data = True
        elif kind == b"IEND":
            break
        pos = end
    if not saw_data:
        raise ImageFileError("cannot be decoded: corrupt (the PNG holds no image data)")
    return ImageFacts(width, height, "image/png")


def _chunk(kind: bytes) -> str:
    return kind.decode("latin-1") if kind.isalpha() else repr(kind)


def _check_pixels(width: int, height: int) -> None:
    if width <= 0 or height <= 0:
        raise ImageFileError(f"cannot be decoded: corrupt (its header says {width}x{height} pixels)")
    if width * height > MAX_PIXELS:
        raise ImageFileError(f"is {width}x{height} pixels, more than the {MAX_PIXELS:,} an image may have")


def _decode_other(data: bytes) -> ImageFacts:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(io.BytesIO(data)) as im:
                _check_pixels(*im.size)
                im.load()
                return ImageFacts(im.width, im.height, f"image/{(im.format or 'png').lower()}")
    except UnidentifiedImageError:
        raise ImageFileError("cannot be decoded: not an image file (no PNG, JPEG or other known image header)") from None
    except (Image.DecompressionBombWarning, Image.DecompressionBombError):
        raise ImageFileError(f"is larger than the {MAX_PIXELS:,} pixels an image may have") from None
    except (OSError, SyntaxError, ValueError, EOFError) as exc:
        reason = "truncated" if "truncated" in str(exc) else f"{type(exc).__name__}: {str(exc)[:200]}"
        raise ImageFileError(f"cannot be decoded: {reason}") from None


def decode_fully(path: Path) -> None:
    """Decode every pixel of ``path`` (what ``validate`` adds on top of the load-time check)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(io.BytesIO(_read_image(path))) as im:
                im.load()
    except UnidentifiedImageError:
        raise ImageFileError("cannot be decoded: not an image file") from None
    except (OSError, SyntaxError, ValueError, EOFError, Image.DecompressionBombWarning, Image.DecompressionBombError) as exc:
        raise ImageFileError(f"cannot be decoded ({type(exc).__name__}: {str(exc)[:200]})") from None


def _read_image(path: Path) -> bytes:
    """The bytes of an image file: a regular file within the image bound, or ImageFileError (a
    pipe or a device there is never waited on or read from)."""
    try:
        return read_regular(path, MAX_IMAGE_FILE_BYTES, what="image file")
    except ReadTargetError as exc:
        raise ImageFileError(exc.reason.removeprefix("image file ")) from None


# -- files, checked once ----------------------------------------------------------------------
_verdicts: dict[tuple[str, int, int], ImageFacts | str] = {}
_lock = threading.Lock()


def inspect_image_file(path: Path) -> ImageFacts:
    """The facts of the image at ``path`` (checked once per file version per process), or
    :class:`ImageFileError` (also for a missing file or a folder)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ImageFileError("does not exist") from None
    except OSError as exc:
        raise ImageFileError(f"cannot be read: {exc.strerror or exc}") from None
    key = (os.fspath(path), st.st_size, st.st_mtime_ns)
    with _lock:
        verdict = _verdicts.get(key)
    if verdict is None:
        try:
            verdict = check_image_bytes(_read_image(path))
        except ImageFileError as exc:
            verdict = str(exc)
        except OSError as exc:
            verdict = f"cannot be read: {exc.strerror or exc}"
        with _lock:
            if len(_verdicts) >= _MAX_REMEMBERED:
                _verdicts.clear()
            _verdicts[key] = verdict
    if isinstance(verdict, str):
        raise ImageFileError(verdict)
    return verdict


def image_problem(path: Path, name: str, size: tuple[int, int] | None, *, decode: bool = False) -> str | None:
    """A sentence saying what is wrong with the image ``name`` at ``path`` (``None``: it is sound).

    ``size`` is its camera's ``(width, height)`` when known; ``decode`` adds a full decode.
    """
    try:
        facts = inspect_image_file(path)
        if decode:
            decode_fully(path)
    except ImageFileError as exc:
        return f"image {shown(name)} {exc}"
    if size is not None and facts.size != tuple(size):
        return f"image {shown(name)} is {facts.width}x{facts.height} but its camera is {size[0]}x{size[1]}"
    return None
