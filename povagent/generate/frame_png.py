"""The PNG bytes of a rendered frame: Pillow's exact bytes, made with numpy and zlib.

What it is for: every RGB frame the generator writes and every view the active mode sends is
PNG-encoded, and the dataset's PNGs are byte-exact (the render tests hold them). Pillow's
encoder picks each row's filter in a C loop that tries four filters byte by byte: about 6 ms
of a 512x512 frame's 13 ms, as much as zlib itself. Here the same choice is made with whole-
array numpy passes over blocks of rows (about 2 ms), or where the compiled loop is built
(``png_rows.c``, :mod:`~povagent.generate.compiled_loops`) in a few integer passes per row in C
that read a renderer's colour planes as they are (about 0.5 ms, no interleaving first), and the
rows go through zlib with Pillow's settings (about 6 ms), so the bytes are Pillow's, byte for
byte (``tests/generate/test_frame_png.py`` holds both paths equal to Pillow). What it must not do: change a byte of the output; any other image
(16-bit masks, agent frames) is Pillow's own business.

The facts of Pillow's PNG writer that the bytes depend on (Pillow's ``ZipEncode.c`` and
``PngImagePlugin.py``, which write no other chunk for a plain RGB image):

* per row, the filter whose bytes have the least sum of ``min(v, 256 - v)`` among none, up,
  sub and paeth, tried in that order, a tie kept by the earlier one (average is tried only
  when optimizing); the row above the first is black;
* zlib at the given level, window 15, ``memLevel`` 9, strategy ``Z_FILTERED``; the stream does
  not depend on how the rows are handed to zlib;
* the stream cut into IDAT chunks of ``max(65536, 4 * width)`` bytes, the last one shorter.
"""

from __future__ import annotations

import struct
import threading
import zlib

import numpy as np
from PIL import Image

from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.thread_buffers import kept_for

#: The compiled row filters (``png_rows.c``), or ``None``: numpy's passes below.
_LOOP = "_png_rows"
_COMPILED = compiled_loop(_LOOP)

#: zlib level for PNGs: 1 gives ~210 KB a 512x512 frame (3: ~190 KB, for more of zlib's CPU), about
#: the size of the release's; the bytes are the same for any number of workers either way.
PNG_COMPRESS_LEVEL = 1
#: Bytes per pixel of an RGB frame: the sub and paeth filters look this many bytes to the left.
_BPP = 3
#: The filters in the order Pillow tries them (a tie keeps the earlier), as PNG filter-type bytes.
_FILTER_TYPES = np.array([0, 2, 1, 4], dtype=np.uint8)  # none, up, sub, paeth
#: Pillow's encoder output buffer (``ImageFile.MAXBLOCK``), which sets the IDAT chunk size.
_IDAT_BLOCK = 65536
#: Bytes of image rows filtered at a time: the filter passes' arrays stay in the CPU's caches
#: (the choice is per row, so the bytes do not depend on the block size).
_FILTER_BLOCK_BYTES = 65536
_SIGNATURE = b"\x89PNG\r\n\x1a\n"


class _RowFilter:
    """The buffers to filter frames of one size, reused frame after frame (a fresh frame-sized
    array costs its page faults every time): one instance per thread (:func:`_filter_for`),
    about 3 MB for 512x512 frames."""

    def __init__(self, height: int, width: int) -> None:
        row = width * _BPP
        self.height, self.row = height, row
        self.rows = max(1, min(height, _FILTER_BLOCK_BYTES // row))
        # the image with a black row above and black pixels to the left, as the filters see it
        self.padded = np.zeros((height + 1, row + _BPP), dtype=np.uint8)
        self.filtered = np.empty((height, row + 1), dtype=np.uint8)  # the chosen rows, as zlib reads them
        k = self.rows
        self.candidates = np.empty((4, k, row + 1), dtype=np.uint8)
        self.candidates[:, :, 0] = _FILTER_TYPES[:, None]
        self.wide = np.empty((k + 1, row + _BPP), dtype=np.int16)
        self.pa, self.pb, self.pc = (np.empty((k, row), dtype=np.int16) for _ in range(3))
        self.is_a, self.is_b, self.flag = (np.empty((k, row), dtype=bool) for _ in range(3))
        self.pick, self.mask, self.other = (np.empty((k, row), dtype=np.uint8) for _ in range(3))
        self.size = np.empty((4, k, row), dtype=np.uint8)
        self.costs = np.empty((4, k), dtype=np.uint32)

    def filter(self, rgb: np.ndarray) -> np.ndarray:
        """The filtered rows (filter-type byte first) of ``rgb`` (height, width, 3), as Pillow
        makes them; a view of a buffer that the next call overwrites."""
        padded = self.padded
        padded[1:, _BPP:] = rgb.reshape(self.height, self.row)
        for top in range(0, self.height, self.rows):
            self._filter_block(top, min(top + self.rows, self.height))
        return self.filtered

    def _filter_block(self, top: int, bottom: int) -> None:
        k = bottom - top
        rows = self.padded[top : bottom + 1]  # the block and the row above it
        x, a, b, c = rows[1:, _BPP:], rows[1:, :-_BPP], rows[:-1, _BPP:], rows[:-1, :-_BPP]
        cand = self.candidates[:, :k]
        none, up, sub, paeth = (cand[i, :, 1:] for i in range(4))
        np.copyto(none, x)
        np.subtract(x, b, out=up)  # uint8 arithmetic wraps modulo 256, as PNG's filters do
        np.subtract(x, a, out=sub)
        self._paeth(k, rows, x, a, b, c, paeth)
        # the cost of a filtered byte v is min(v, 256 - v): |v| read as a signed byte (-128 stays 128)
        size = self.size[:, :k]
        np.abs(cand[:, :, 1:].view(np.int8), out=size.view(np.int8))
        costs = np.sum(size, axis=2, dtype=np.uint32, out=self.costs[:, :k])
        choice = np.argmin(costs, axis=0)  # the first of equal costs: Pillow's strict "less than"
        choice *= k
        choice += np.arange(k)
        np.take(cand.reshape(4 * k, -1), choice, axis=0, out=self.filtered[top:bottom])

    def _paeth(self, k: int, rows: np.ndarray, x: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
        """PNG's paeth filter of a block: ``x`` minus whichever of left ``a``, above ``b`` and
        above-left ``c`` is nearest ``a + b - c`` (ties to ``a``, then ``b``)."""
        wide = self.wide[: k + 1]
        np.copyto(wide, rows)
        a16, b16, c16 = wide[1:, :-_BPP], wide[:-1, _BPP:], wide[:-1, :-_BPP]
        pa, pb, pc = self.pa[:k], self.pb[:k], self.pc[:k]
        np.subtract(b16, c16, out=pa)  # |p - a| with p = a + b - c
        np.subtract(a16, c16, out=pb)  # |p - b|
        np.add(pa, pb, out=pc)  # |p - c|
        np.abs(pa, out=pa)
        np.abs(pb, out=pb)
        np.abs(pc, out=pc)
        is_a, is_b, flag = self.is_a[:k], self.is_b[:k], self.flag[:k]
        np.less_equal(pa, pb, out=is_a)
        is_a &= np.less_equal(pa, pc, out=flag)
        np.less_equal(pb, pc, out=flag)
        np.greater(flag, is_a, out=is_b)  # b where not a and pb <= pc
        # the predictor by byte masks (0 or 255): a & A | b & B | c & ~(A | B), no branches
        pick, mask, other = self.pick[:k], self.mask[:k], self.other[:k]
        np.negative(is_a.view(np.uint8), out=mask)
        np.bitwise_and(a, mask, out=pick)
        np.negative(is_b.view(np.uint8), out=other)
        mask |= other
        other &= b
        pick |= other
        np.invert(mask, out=mask)
        mask &= c
        pick |= mask
        np.subtract(x, pick, out=out)


_THREAD = threading.local()


def _filter_for(height: int, width: int) -> _RowFilter:
    """This thread's buffers for frames of ``width`` x ``height`` (the last size kept)."""
    return kept_for(_THREAD, "row_filter", (height, width), lambda: _RowFilter(height, width))


def _rows_for(height: int, width: int) -> np.ndarray:
    """This thread's buffer for the compiled loop's filtered rows of a frame of this size (the
    last size kept)."""
    return kept_for(_THREAD, "rows", (height, width), lambda: np.empty((height, width * _BPP + 1), dtype=np.uint8))


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(data, zlib.crc32(kind)))


def encode_frame_png(rgb: np.ndarray, compress_level: int = PNG_COMPRESS_LEVEL) -> bytes:
    """The PNG bytes Pillow writes for the RGB image ``rgb`` (height, width, 3) uint8 with
    ``compress_level`` and no metadata (``Image.fromarray(rgb).save(f, "PNG", compress_level=...)``)."""
    if rgb.ndim != 3 or rgb.shape[2] != _BPP or rgb.dtype != np.uint8 or not rgb.size:
        raise ValueError(f"an RGB frame is (height, width, 3) uint8, not {rgb.shape} {rgb.dtype}")
    height, width = rgb.shape[:2]
    if _COMPILED is not None:
        rows = _rows_for(height, width)
        _COMPILED.filter_rows(np.ascontiguousarray(rgb), height, width, False, rows)
    else:
        rows = _filter_for(height, width).filter(rgb)
    return _png_of_rows(rows, height, width, compress_level)


def encode_planes_png(planes: np.ndarray, height: int, width: int, compress_level: int = PNG_COMPRESS_LEVEL) -> bytes:
    """:func:`encode_frame_png` of the image whose red, green and blue bytes are the rows of
    ``planes`` (3, height * width) uint8 (a renderer's colour planes), without interleaving them
    first where the compiled loop is built (it reads the planes as they are)."""
    if planes.shape != (3, height * width) or planes.dtype != np.uint8 or not planes.size:
        raise ValueError(f"colour planes are (3, {height} * {width}) uint8, not {planes.shape} {planes.dtype}")
    if _COMPILED is None:
        # Pillow interleaves the planes in one C pass (numpy's copy into every third byte costs
        # several times more)
        size = (width, height)
        image = Image.merge("RGB", [Image.frombuffer("L", size, np.ascontiguousarray(plane), "raw", "L", 0, 1) for plane in planes])
        rgb = np.frombuffer(image.tobytes(), dtype=np.uint8).reshape(height, width, _BPP)
        return encode_frame_png(rgb, compress_level)
    rows = _rows_for(height, width)
    _COMPILED.filter_rows(np.ascontiguousarray(planes), height, width, True, rows)
    return _png_of_rows(rows, height, width, compress_level)


def _png_of_rows(rows: np.ndarray, height: int, width: int, compress_level: int) -> bytes:
    """The PNG file of filtered ``rows`` (each row's filter-type byte first)."""
    deflate = zlib.compressobj(compress_level, zlib.DEFLATED, 15, 9, zlib.Z_FILTERED)
    stream = deflate.compress(rows.data) + deflate.flush()  # the buffer read in place, no copy
    step = max(_IDAT_BLOCK, 4 * width)
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)  # 8 bits, RGB, deflate, no interlace
    parts = [_SIGNATURE, _chunk(b"IHDR", header)]
    parts += [_chunk(b"IDAT", stream[k : k + step]) for k in range(0, len(stream), step)]
    parts.append(_chunk(b"IEND", b""))
    return b"".join(parts)
