"""Letterbox rules (the paper resizes real frames "to 512 x 512 using letterbox padding"), one per test.

The contract (povagent/geometry/letterbox.py): scale s = 512 / max(w, h) to (round(w s), round(h s)),
paste centred with integer offsets, an odd remainder going right/bottom; coordinates are
continuous with (W, H) the far corner; mapping back clamps to [0, W] x [0, H].
"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from povagent.geometry.letterbox import BENCHMARK_SIZE, Letterbox, letterbox, pixel_index


def test_benchmark_frames_are_512_square():
    assert BENCHMARK_SIZE == 512


@pytest.mark.parametrize(("w", "h"), [(512, 300), (300, 512), (1024, 1024), (511, 512)])
def test_only_a_512_square_frame_is_the_identity(w, h):
    assert not Letterbox.for_size(w, h).is_identity
    assert Letterbox.for_size(512, 512).is_identity


def test_a_wide_frame_is_padded_top_and_bottom_with_the_odd_pixel_at_the_bottom():
    box = Letterbox.for_size(512, 301)
    assert box.resized == (512, 301)
    assert box.offset == (0, 105)  # 211 rows of padding: 105 above, 106 below
    assert box.content_box() == (0, 105, 512, 406)


def test_a_tall_frame_is_padded_left_and_right():
    box = Letterbox.for_size(300, 600)
    assert box.resized == (256, 512)
    assert box.offset == (128, 0)


def test_the_scaled_size_is_rounded_not_truncated():
    assert Letterbox.for_size(1000, 563).resized == (512, 288)
    assert Letterbox.for_size(1000, 565).resized == (512, 289)


def test_a_thin_strip_keeps_at_least_one_pixel():
    assert Letterbox.for_size(5000, 1).resized == (512, 1)
    assert Letterbox.for_size(1, 5000).resized == (1, 512)  # a 1-pixel-wide strip too


def test_a_frame_smaller_than_512_is_scaled_up():
    box = Letterbox.for_size(256, 128)
    assert box.resized == (512, 256)
    assert box.scale == (2.0, 2.0)
    assert box.offset == (0, 128)


@pytest.mark.parametrize(("w", "h"), [(0, 10), (10, 0), (-1, 5)])
def test_an_empty_frame_is_refused(w, h):
    with pytest.raises(ValueError, match="positive"):
        Letterbox.for_size(w, h)


def test_to_square_and_back_is_exact():
    box = Letterbox.for_size(1000, 563)
    pts = np.array([[0.0, 0.0], [1000.0, 563.0], [123.4, 456.7]])
    sq = box.to_square(pts)
    assert np.allclose(sq[0], [0.0, 112.0])
    assert np.allclose(sq[1], [512.0, 400.0])
    assert np.allclose(box.to_original(sq), pts, atol=1e-9)


def test_a_point_on_the_padding_maps_back_to_the_nearest_edge():
    box = Letterbox.for_size(1000, 563)
    assert np.allclose(box.to_original([256.0, 5.0]), [500.0, 0.0])
    assert np.allclose(box.to_original([256.0, 510.0]), [500.0, 563.0])
    assert np.allclose(box.to_original([256.0, 5.0], clamp=False)[1], (5.0 - 112.0) * 563 / 288)


def test_on_padding_is_outside_the_content_box_inclusive_edges():
    box = Letterbox.for_size(1000, 563)
    assert not box.on_padding((0.0, 112.0)) and not box.on_padding((512.0, 400.0))
    assert box.on_padding((256.0, 111.9)) and box.on_padding((256.0, 400.1))
    tall = Letterbox.for_size(300, 600)
    assert tall.on_padding((127.9, 300.0)) and tall.on_padding((384.1, 300.0))
    assert not tall.on_padding((128.0, 300.0))


def test_the_image_is_pasted_at_the_offset_on_padding_of_the_pad_colour():
    image = Image.new("RGB", (100, 50), (200, 10, 10))
    square, box = letterbox(image, pad_color=(1, 2, 3))
    assert square.size == (512, 512)
    assert box.offset == (0, 128)
    assert square.getpixel((256, 127)) == (1, 2, 3)
    assert square.getpixel((256, 128)) == (200, 10, 10)
    assert square.getpixel((256, 383)) == (200, 10, 10)
    assert square.getpixel((256, 384)) == (1, 2, 3)


def test_a_512_square_image_passes_through_unchanged():
    image = Image.new("RGB", (512, 512), (9, 9, 9))
    square, box = letterbox(image)
    assert box.is_identity and square.tobytes() == image.tobytes()


@pytest.mark.parametrize("size", [(50, 100), (200, 50), (100, 60)])
def test_apply_refuses_an_image_of_another_size(size):
    with pytest.raises(ValueError, match=f"image is {size[0]}x{size[1]}, the letterbox was made for 100x50"):
        Letterbox.for_size(100, 50).apply(Image.new("RGB", size))


def test_the_default_padding_is_black():
    square, _ = letterbox(Image.new("RGB", (100, 50), (200, 10, 10)))
    assert square.getpixel((256, 5)) == (0, 0, 0)


def test_a_letterbox_is_a_value_that_cannot_be_altered():
    import dataclasses

    with pytest.raises(dataclasses.FrozenInstanceError):
        Letterbox.for_size(100, 50).offset = (0, 0)  # type: ignore[misc]


@pytest.mark.parametrize(("point", "expected"), [((512.0, 3.2), (511, 3)), ((-4.0, 600.0), (0, 511)), ((3.0, -4.0), (3, 0)), ((10.99, 0.0), (10, 0))])
def test_pixel_index_floors_and_clamps_to_the_frame(point, expected):
    assert pixel_index(point, 512, 512) == expected
