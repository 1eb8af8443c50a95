"""The letterbox transform: exact both ways, and the same transform the pixels went through."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from povagent.geometry.letterbox import Letterbox, letterbox, pixel_index

sizes = st.tuples(st.integers(1, 4000), st.integers(1, 4000))


@given(sizes, st.floats(0, 1), st.floats(0, 1))
@settings(max_examples=300, deadline=None)
def test_original_point_round_trips_through_the_square(size, fx, fy):
    box = Letterbox.for_size(*size)
    p = np.array([fx * size[0], fy * size[1]])
    back = box.to_original(box.to_square(p))
    assert np.allclose(back, p, rtol=0, atol=1e-9 * max(size))


@given(sizes, st.floats(0, 1), st.floats(0, 1))
@settings(max_examples=300, deadline=None)
def test_square_point_on_content_round_trips_through_the_original(size, fx, fy):
    box = Letterbox.for_size(*size)
    left, top, right, bottom = box.content_box()
    q = np.array([left + fx * (right - left), top + fy * (bottom - top)])
    assert np.allclose(box.to_square(box.to_original(q)), q, rtol=0, atol=1e-9)


@given(sizes)
@settings(max_examples=200, deadline=None)
def test_content_is_centred_and_fills_the_long_side(size):
    box = Letterbox.for_size(*size)
    rw, rh = box.resized
    assert max(rw, rh) == 512
    assert abs(box.offset[0] - (512 - rw) / 2) <= 0.5 and abs(box.offset[1] - (512 - rh) / 2) <= 0.5
    # the short side keeps the aspect ratio, rounded to whole pixels (never below one)
    s = 512 / max(size)
    assert (rw, rh) == (max(1, round(size[0] * s)), max(1, round(size[1] * s)))


@given(sizes, st.floats(-600, 1200), st.floats(-600, 1200))
@settings(max_examples=200, deadline=None)
def test_points_on_the_padding_are_clamped_into_the_original_frame(size, x, y):
    box = Letterbox.for_size(*size)
    px, py = box.to_original(np.array([x, y]))
    assert 0 <= px <= size[0] and 0 <= py <= size[1]


def test_square_frames_are_left_unchanged():
    box = Letterbox.for_size(512, 512)
    assert box.is_identity and box.offset == (0, 0) and box.scale == (1.0, 1.0)
    im = Image.new("RGB", (512, 512), (10, 20, 30))
    assert box.apply(im).tobytes() == im.tobytes()


def test_wide_frame_is_padded_top_and_bottom():
    box = Letterbox.for_size(1920, 1080)
    assert box.resized == (512, 288) and box.offset == (0, 112)


def test_tall_frame_is_padded_left_and_right():
    box = Letterbox.for_size(480, 640)
    assert box.resized == (384, 512) and box.offset == (64, 0)


def test_small_frames_are_scaled_up():
    box = Letterbox.for_size(64, 32)
    assert box.resized == (512, 256)


def test_a_marked_pixel_lands_where_the_transform_says():
    # a bright block in a dark wide frame: its centre must map to the centre of the bright
    # region of the letterboxed image (checks the transform against Pillow's resampling)
    w, h = 1280, 720
    a = np.zeros((h, w, 3), np.uint8)
    a[300:340, 900:960] = 255
    square, box = letterbox(Image.fromarray(a))
    s = np.asarray(square)[..., 0].astype(float)
    ys, xs = np.nonzero(s > 127)
    measured = np.array([xs.mean() + 0.5, ys.mean() + 0.5])  # pixel centres
    expected = box.to_square(np.array([930.0, 320.0]))
    assert np.allclose(measured, expected, atol=0.6)


def test_padding_has_the_pad_colour():
    square, _box = letterbox(Image.new("RGB", (200, 100), (255, 255, 255)), pad_color=(7, 8, 9))
    assert square.size == (512, 512)
    assert square.getpixel((5, 5)) == (7, 8, 9)
    assert square.getpixel((256, 256)) == (255, 255, 255)


def test_apply_rejects_an_image_of_another_size():
    with pytest.raises(ValueError, match="letterbox was made for"):
        Letterbox.for_size(100, 50).apply(Image.new("RGB", (50, 100)))


def test_pixel_index_puts_the_right_edge_in_the_last_column():
    assert pixel_index((640.0, 360.0), 640, 360) == (639, 359)
    assert pixel_index((0.0, 0.0), 640, 360) == (0, 0)
    assert pixel_index((10.7, 3.2), 640, 360) == (10, 3)
