"""The frame encoder writes Pillow's PNG bytes, byte for byte (the dataset's PNGs stay as they were)."""

from __future__ import annotations

import io
import shutil
import sys
import threading
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from povagent.generate import frame_png
from povagent.generate.compiled_loops import compiled_loop
from povagent.generate.frame_png import PNG_COMPRESS_LEVEL, encode_frame_png, encode_planes_png
from tests.generate.compiled_paths import OTHER_BUILDS, each_path, other_build

#: every test here runs on the compiled row filters and on numpy's (the same bytes)
path = pytest.fixture(autouse=True, params=["compiled", "numpy"])(each_path(frame_png))


def pillow_png(rgb: np.ndarray, level: int = PNG_COMPRESS_LEVEL) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="PNG", compress_level=level)
    return buf.getvalue()


def filter_types(png: bytes, height: int, width: int) -> set[int]:
    """The PNG filter type of each row (the first byte of each row of the inflated IDAT data)."""
    pos, idat = 8, b""
    while pos < len(png):
        size = int.from_bytes(png[pos : pos + 4], "big")
        if png[pos + 4 : pos + 8] == b"IDAT":
            idat += png[pos + 8 : pos + 8 + size]
        pos += 12 + size
    rows = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, 3 * width + 1)
    return set(rows[:, 0].tolist())


def test_the_exploration_frames_written_are_pillows_png_of_their_pixels(tiny_dataset):
    frames = sorted((tiny_dataset.house_dir / "exploration_images").glob("*.png"))
    assert frames
    for path in frames:
        data = path.read_bytes()
        assert data == pillow_png(np.array(Image.open(io.BytesIO(data)))), path.name


def _images() -> list[np.ndarray]:
    rng = np.random.default_rng(5)
    ramp = (np.arange(64 * 96 * 3, dtype=np.int64).reshape(64, 96, 3) * 7 % 251).astype(np.uint8)
    bands = np.repeat(rng.integers(0, 256, (64, 1, 3), dtype=np.uint8), 96, axis=1)  # rows of one colour
    columns = np.repeat(rng.integers(0, 256, (1, 96, 3), dtype=np.uint8), 64, axis=0)  # every row the same
    smooth = np.clip(ramp // 4 + rng.integers(0, 3, ramp.shape), 0, 255).astype(np.uint8)
    return [
        np.zeros((64, 96, 3), dtype=np.uint8),
        rng.integers(0, 256, (64, 96, 3), dtype=np.uint8),
        ramp, bands, columns, smooth,
        np.full((1, 1, 3), 128, dtype=np.uint8),
        rng.integers(0, 256, (3, 5, 3), dtype=np.uint8),
    ]  # fmt: skip


@pytest.mark.parametrize("index", range(len(_images())))
def test_an_image_of_any_content_and_size_encodes_to_pillows_bytes(index):
    rgb = _images()[index]
    assert encode_frame_png(rgb) == pillow_png(rgb)


def test_the_images_above_make_pillow_choose_every_filter():
    used = set().union(*(filter_types(pillow_png(rgb), *rgb.shape[:2]) for rgb in _images()))
    assert used == {0, 1, 2, 4}  # none, sub, up, paeth (Pillow tries average only when optimizing)


def test_a_frame_too_wide_for_one_pillow_buffer_row_is_cut_into_pillows_idat_chunks():
    rgb = np.random.default_rng(6).integers(0, 256, (3, 20000, 3), dtype=np.uint8)  # 4 * width > 65536
    assert encode_frame_png(rgb) == pillow_png(rgb)


@pytest.mark.parametrize("index", range(len(_images())))
def test_colour_planes_encode_to_the_bytes_of_their_interleaved_frame(index):
    rgb = _images()[index]
    height, width = rgb.shape[:2]
    planes = np.ascontiguousarray(rgb.reshape(-1, 3).T)
    assert encode_planes_png(planes, height, width) == pillow_png(rgb)


@pytest.mark.skipif((shutil.which("cc") is None and shutil.which("gcc") is None) or sys.platform == "win32", reason="no C compiler to build the generic loop")
@OTHER_BUILDS
def test_the_row_filters_built_for_another_cpu_give_the_installed_ones_bytes(tmp_path, monkeypatch, extra):
    """The installed loop filters rows with AVX-512 or AVX2 where the CPU has them; built for any
    x86-64, or as the AVX2 clone, it writes the same filtered rows, for planes and for
    interleaved pixels."""
    generic = other_build(tmp_path, "png_rows", extra)
    for rgb in [*_images(), np.random.default_rng(8).integers(0, 256, (37, 515, 3), dtype=np.uint8)]:
        height, width = rgb.shape[:2]
        planes = np.ascontiguousarray(rgb.reshape(-1, 3).T)
        encoded = []
        for loop in (compiled_loop(frame_png._LOOP), generic):
            if loop is None:
                pytest.skip("the compiled loop is not built here (or POVAGENT_PURE_NUMPY is set)")
            monkeypatch.setattr(frame_png, "_COMPILED", loop)
            encoded.append((encode_frame_png(rgb), encode_planes_png(planes, height, width)))
        assert encoded[0] == encoded[1] == (pillow_png(rgb), pillow_png(rgb))


def test_planes_of_another_shape_are_refused():
    with pytest.raises(ValueError, match="colour planes"):
        encode_planes_png(np.zeros((3, 10), dtype=np.uint8), 3, 4)


@pytest.mark.parametrize("level", [0, 6, 9])
def test_other_compression_levels_give_pillows_bytes_too(level):
    rgb = _images()[5]
    assert encode_frame_png(rgb, level) == pillow_png(rgb, level)


def test_threads_encoding_frames_of_other_sizes_at_once_each_get_their_own_bytes():
    images = _images()[:6]
    expected = [pillow_png(rgb) for rgb in images]
    results: dict[int, list[bool]] = {}

    def encode(k: int) -> None:
        rgb = images[k] if k % 2 else images[k][:40, :50].copy()
        want = expected[k] if k % 2 else pillow_png(rgb)
        results[k] = [encode_frame_png(rgb) == want for _ in range(20)]

    threads = [threading.Thread(target=encode, args=(k,)) for k in range(len(images))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert results == {k: [True] * 20 for k in range(len(images))}


@pytest.mark.parametrize("shape, dtype", [((4, 4), np.uint8), ((4, 4, 4), np.uint8), ((4, 4, 3), np.uint16)])
def test_anything_but_an_rgb_byte_frame_is_refused(shape, dtype):
    with pytest.raises(ValueError, match="RGB frame"):
        encode_frame_png(np.zeros(shape, dtype=dtype))


def test_a_written_frame_file_is_the_encoders_bytes(tmp_path: Path):
    from povagent.generate.writer import write_png

    rgb = _images()[1]
    write_png(tmp_path / "f.png", rgb)
    assert (tmp_path / "f.png").read_bytes() == pillow_png(rgb)
