"""Frames shown by the agent: letterboxed, named and encoded once, encoded only when a backend
sends pixels, files of the benchmark's size passed through as they are."""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest
from PIL import Image

from povagent.agent import GroundingAgent, ShownFrame
from povagent.errors import BadInputError
from povagent.geometry.letterbox import Letterbox
from povagent.testing.loopback_server import LoopbackServer

KEY_ENV = "POVAGENT_SHOWN_FRAME_TEST_KEY"


def wide_frames(n: int = 3) -> list[np.ndarray]:
    """``n`` 640x480 RGB arrays, each a different pattern."""
    rng = np.random.default_rng(7)
    return [rng.integers(0, 255, size=(480, 640, 3), dtype=np.uint8) for _ in range(n)]


@pytest.fixture
def png_saves(monkeypatch):
    """How many times any image is saved as PNG (the real save runs: this only counts)."""
    calls = []
    real_save = Image.Image.save

    def counting_save(self, fp, format=None, **params):
        if (format or "").upper() == "PNG":
            calls.append(self.size)
        return real_save(self, fp, format, **params)

    monkeypatch.setattr(Image.Image, "save", counting_save)
    return calls


@pytest.fixture
def model_agent(monkeypatch):
    """An agent on the litellm backend talking to a loopback model server."""
    monkeypatch.setenv(KEY_ENV, "test-key")
    with LoopbackServer(reply='{"selected_image": 0, "x": 256, "y": 256}', max_lifetime_s=60) as server:
        agent = GroundingAgent(
            "litellm",
            backend_options={"model": "openai/loopback", "api_base": server.url, "api_key_env": KEY_ENV, "timeout": 10},
            timeout_s=20,
        )
        try:
            yield agent, server
        finally:
            agent.close()


def sent_png_bytes(request) -> list[bytes]:
    """The encoded images a recorded request carried."""
    return [
        base64.b64decode(part["image_url"]["url"].split(",", 1)[1])
        for part in request.user_parts()
        if part.get("type") == "image_url"
    ]


def png_of(image: Image.Image) -> bytes:
    buf = io.BytesIO()
    image.save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


def test_the_center_baseline_never_encodes_a_frame(png_saves):
    with GroundingAgent("center") as agent:
        agent.locate("my mug is to the right of the kettle", wide_frames())
    assert png_saves == []


def test_a_model_is_sent_each_letterboxed_frame_as_the_png_it_was_sent_before(model_agent):
    agent, server = model_agent
    frames = wide_frames(2)
    agent.locate("the mug", frames)
    squares = [Letterbox.for_size(640, 480).apply(Image.fromarray(f)) for f in frames]
    assert sent_png_bytes(server.requests[0]) == [png_of(s) for s in squares]


def test_a_shown_frame_is_encoded_once_however_many_calls_show_it(model_agent, png_saves):
    agent, server = model_agent
    shown = [ShownFrame(f) for f in wide_frames(3)]
    agent.locate("the mug", shown)
    agent.locate("the kettle", shown)
    assert len(png_saves) == 3
    assert sent_png_bytes(server.requests[0]) == sent_png_bytes(server.requests[1])


def test_a_benchmark_size_png_file_is_sent_as_it_is(model_agent, tmp_path, png_saves):
    agent, server = model_agent
    path = tmp_path / "square.png"
    Image.fromarray(wide_frames(1)[0][:, :480].repeat(2, axis=0)[:512, :].copy()).resize((512, 512)).save(path, compress_level=9)
    png_saves.clear()
    agent.locate("the mug", [str(path)])
    assert sent_png_bytes(server.requests[0]) == [path.read_bytes()] and png_saves == []


def test_a_benchmark_size_file_that_is_not_rgb_is_converted_as_before(model_agent, tmp_path):
    agent, server = model_agent
    path = tmp_path / "square.png"
    Image.new("RGBA", (512, 512), (10, 20, 30, 128)).save(path)
    agent.locate("the mug", [path])
    assert sent_png_bytes(server.requests[0]) == [png_of(Image.new("RGB", (512, 512), (10, 20, 30)))]


def test_a_truncated_benchmark_size_file_is_refused_naming_the_frame(tmp_path):
    path = tmp_path / "square.png"
    Image.new("RGB", (512, 512), (1, 2, 3)).save(path)
    path.write_bytes(path.read_bytes()[:-30])
    with GroundingAgent("center") as agent, pytest.raises(BadInputError, match=r"frames\[0\]: .*square\.png"):
        agent.locate("the mug", [path])


def test_an_agent_with_another_pad_colour_letterboxes_a_shown_frame_afresh(model_agent):
    agent, server = model_agent
    agent.pad_color = (255, 0, 0)
    frame = wide_frames(1)[0]
    agent.locate("the mug", [ShownFrame(frame)])  # made with the default (black) padding
    expected = Letterbox.for_size(640, 480).apply(Image.fromarray(frame), (255, 0, 0))
    assert sent_png_bytes(server.requests[0]) == [png_of(expected)]
