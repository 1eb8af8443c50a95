"""sensor_msgs images to RGB arrays and depth in metres (messages stood in for by plain objects
with the same field names, as both rclpy and rosbags give them)."""

from __future__ import annotations

import io
import struct
from types import SimpleNamespace

import numpy as np
import pytest
from PIL import Image

from povagent.ros.image_messages import MAX_PIXELS, ImageProblem, compressed_to_rgb, depth_to_metres, image_to_rgb

RGB = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3) * 10


def message(pixels: np.ndarray, encoding: str, pad: int = 0, data=None) -> SimpleNamespace:
    h, w = pixels.shape[:2]
    row = pixels.reshape(h, -1).view(np.uint8) if pixels.dtype != np.uint8 else pixels.reshape(h, -1)
    padded = np.concatenate([row, np.zeros((h, pad), dtype=np.uint8)], axis=1)
    return SimpleNamespace(height=h, width=w, encoding=encoding, step=padded.shape[1], is_bigendian=0,
                           data=padded.tobytes() if data is None else data, header=None)


@pytest.mark.parametrize(("encoding", "stored"), [
    ("rgb8", RGB),
    ("bgr8", RGB[..., ::-1]),
    ("rgba8", np.concatenate([RGB, np.full((2, 3, 1), 7, np.uint8)], axis=2)),
    ("bgra8", np.concatenate([RGB[..., ::-1], np.full((2, 3, 1), 7, np.uint8)], axis=2)),
])
def test_each_colour_encoding_reads_as_the_same_rgb(encoding, stored):
    assert np.array_equal(image_to_rgb(message(stored, encoding)), RGB)


def test_mono8_reads_as_three_equal_channels():
    grey = RGB[..., 0]
    out = image_to_rgb(message(grey[..., None], "mono8"))
    assert out.shape == (2, 3, 3) and all(np.array_equal(out[..., c], grey) for c in range(3))


def test_row_padding_beyond_the_width_is_cut():
    assert np.array_equal(image_to_rgb(message(RGB, "rgb8", pad=5)), RGB)


def test_rclpy_array_data_reads_like_bytes():
    import array

    msg = message(RGB, "rgb8")
    msg.data = array.array("B", msg.data)
    assert np.array_equal(image_to_rgb(msg), RGB)


def test_an_unknown_encoding_is_an_encoding_problem():
    with pytest.raises(ImageProblem, match="yuv422") as info:
        image_to_rgb(message(RGB, "yuv422"))
    assert info.value.kind == "encoding"


@pytest.mark.parametrize("broken", ["zero size", "short data", "short step"])
def test_a_size_that_does_not_add_up_is_a_size_problem(broken):
    msg = message(RGB, "rgb8")
    if broken == "zero size":
        msg.width = 0
    elif broken == "short data":
        msg.data = msg.data[:-1]
    else:
        msg.step = 8
    with pytest.raises(ImageProblem) as info:
        image_to_rgb(msg)
    assert info.value.kind == "size"


def test_a_huge_claimed_size_is_refused_before_reading():
    msg = message(RGB, "rgb8")
    msg.width, msg.height, msg.step = 100_000, 100_000, 300_000
    with pytest.raises(ImageProblem, match="over the pixel budget"):
        image_to_rgb(msg)


def jpeg_header(width: int, height: int) -> bytes:
    """A real 16x16 JPEG whose frame header (SOF0) is rewritten to claim ``width`` x ``height``."""
    buf = io.BytesIO()
    Image.fromarray(np.zeros((16, 16, 3), np.uint8)).save(buf, format="JPEG")
    data = bytearray(buf.getvalue())
    sof = data.index(b"\xff\xc0")
    data[sof + 5:sof + 9] = struct.pack(">HH", height, width)
    return bytes(data)


@pytest.mark.parametrize(("fmt", "header"), [("png", None), ("jpeg", jpeg_header)])
def test_a_compressed_image_over_the_pixel_budget_is_refused_from_its_header_never_decoded(fmt, header, claimed_png):
    header = claimed_png if header is None else header
    with pytest.raises(ImageProblem, match=r"6000x6000 pixels is over the pixel budget") as info:
        compressed_to_rgb(SimpleNamespace(format=fmt, data=header(6000, 6000)))
    assert info.value.kind == "pixel_budget"


def test_an_image_at_the_pixel_budget_goes_on_to_be_decoded_and_one_row_more_does_not(claimed_png):
    width = 4096
    height = MAX_PIXELS // width
    raw = message(RGB, "rgb8")  # claims the budget's size, holds 18 bytes: reading it fails on its data
    raw.width, raw.height, raw.step = width, height, 3 * width
    kinds = []
    for rows in (height, height + 1):
        raw.height = rows
        for decode, msg in ((image_to_rgb, raw), (compressed_to_rgb, SimpleNamespace(format="png", data=claimed_png(width, rows)))):
            with pytest.raises(ImageProblem) as info:
                decode(msg)
            kinds.append(info.value.kind)
    assert kinds == ["size", "compressed", "pixel_budget", "pixel_budget"]


def test_a_raw_image_over_the_pixel_budget_is_its_own_kind_whatever_its_data():
    msg = message(RGB, "rgb8")
    msg.width, msg.height, msg.step = 6000, 6000, 18000
    with pytest.raises(ImageProblem) as info:
        image_to_rgb(msg)
    assert info.value.kind == "pixel_budget"
    depth = message(np.zeros((2, 3), "<u2")[..., None], "16UC1")
    depth.width, depth.height, depth.step = 6000, 6000, 12000
    with pytest.raises(ImageProblem) as info:
        depth_to_metres(depth)
    assert info.value.kind == "pixel_budget"


@pytest.mark.parametrize(("fmt", "pil"), [("png", "PNG"), ("rgb8; jpeg compressed bgr8", "JPEG")])
def test_compressed_png_and_jpeg_decode_to_rgb(fmt, pil):
    big = np.kron(RGB, np.ones((8, 8, 1), dtype=np.uint8))  # JPEG needs more than a few pixels
    buf = io.BytesIO()
    Image.fromarray(big).save(buf, format=pil, quality=100)
    out = compressed_to_rgb(SimpleNamespace(format=fmt, data=buf.getvalue()))
    assert out.shape == big.shape
    assert np.abs(out.astype(int) - big).max() <= (0 if pil == "PNG" else 12)


def test_compressed_garbage_is_a_compressed_problem():
    with pytest.raises(ImageProblem) as info:
        compressed_to_rgb(SimpleNamespace(format="png", data=b"not a png at all"))
    assert info.value.kind == "compressed"


def test_a_compressed_format_other_than_jpeg_or_png_is_refused():
    with pytest.raises(ImageProblem, match="neither jpeg nor png"):
        compressed_to_rgb(SimpleNamespace(format="tiff", data=b"II*\x00"))


def test_16uc1_depth_is_millimetres_with_zero_as_a_hole():
    mm = np.array([[1000, 0], [2500, 65535]], dtype="<u2")
    out = depth_to_metres(message(mm[..., None], "16UC1"))
    assert out[0, 0] == 1.0 and np.isnan(out[0, 1]) and out[1, 0] == 2.5


def test_32fc1_depth_is_metres_with_nan_and_zero_as_holes():
    m = np.array([[1.25, np.nan], [0.0, 3.5]], dtype="<f4")
    out = depth_to_metres(message(m[..., None], "32FC1"))
    assert out[0, 0] == 1.25 and np.isnan(out[0, 1]) and np.isnan(out[1, 0]) and out[1, 1] == 3.5


def test_big_endian_depth_is_read_as_such():
    mm = np.array([[1000, 2000]], dtype=">u2")
    msg = message(mm[..., None], "16UC1")
    msg.is_bigendian = 1
    assert depth_to_metres(msg).tolist() == [[1.0, 2.0]]
