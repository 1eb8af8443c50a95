"""Frames handed to the agent bare, again: known by their content, letterboxed and encoded once;
changed content is a new frame; frames no backend reads are never letterboxed."""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest
from PIL import Image

from povagent.agent import GroundingAgent
from povagent.agent.frame_memory import FrameMemory
from povagent.exchange.messages import Response
from povagent.geometry.letterbox import DEFAULT_PAD_COLOR, Letterbox
from povagent.interfaces import Backend


class SendsPixels(Backend):
    """A model that is sent every image's bytes (as a remote model is) and answers the centre."""

    cacheable = False

    def __init__(self) -> None:
        self.sent: list[list[bytes]] = []

    def identity(self) -> dict:
        return {"backend": "sends-pixels"}

    async def complete(self, request, images):
        urls = [images.data_url(h) for h in request.image_hashes()]
        self.sent.append([base64.b64decode(u.split(",", 1)[1]) for u in urls])
        return Response(text='{"selected_image": 0, "x": 256, "y": 256}')


def wide_frames(n: int = 3) -> list[np.ndarray]:
    """``n`` 640x480 RGB arrays, each a different pattern."""
    rng = np.random.default_rng(11)
    return [rng.integers(0, 255, size=(480, 640, 3), dtype=np.uint8) for _ in range(n)]


def png_of(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Letterbox.for_size(array.shape[1], array.shape[0]).apply(Image.fromarray(array)).save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


@pytest.fixture
def letterboxes(monkeypatch):
    """How many frames are letterboxed (the real letterbox runs: this only counts)."""
    calls = []
    real_apply = Letterbox.apply

    def counting_apply(self, image, pad_color=DEFAULT_PAD_COLOR):
        calls.append(self.original)
        return real_apply(self, image, pad_color)

    monkeypatch.setattr(Letterbox, "apply", counting_apply)
    return calls


@pytest.fixture
def pixel_agent():
    backend = SendsPixels()
    with GroundingAgent(backend, parser="json") as agent:
        yield agent, backend


def test_the_same_arrays_again_are_letterboxed_once_and_sent_as_the_same_bytes(pixel_agent, letterboxes):
    agent, backend = pixel_agent
    frames = wide_frames(3)
    agent.locate("the mug", frames)
    agent.locate("the kettle", [f.copy() for f in frames])  # equal content, other arrays
    assert len(letterboxes) == 3
    assert backend.sent[0] == backend.sent[1] == [png_of(f) for f in frames]


def test_an_array_changed_in_place_after_a_call_is_shown_with_its_new_pixels(pixel_agent):
    agent, backend = pixel_agent
    (frame,) = wide_frames(1)
    agent.locate("the mug", [frame])
    frame[:100] = 7  # the app writes its next image into the same buffer
    agent.locate("the mug", [frame])
    assert backend.sent[1] == [png_of(frame)] != backend.sent[0]


def test_a_remembered_array_keeps_the_pixels_it_was_first_handed_with(pixel_agent):
    agent, backend = pixel_agent
    (frame,) = wide_frames(1)
    first = frame.copy()
    agent.locate("the mug", [frame])  # remembered (a copy), encoded
    frame[:] = 0
    agent.locate("the mug", [first])
    assert backend.sent[1] == backend.sent[0] == [png_of(first)]


def test_the_same_file_again_is_decoded_and_letterboxed_once(pixel_agent, letterboxes, tmp_path):
    agent, backend = pixel_agent
    path = tmp_path / "frame.png"
    Image.fromarray(wide_frames(1)[0]).save(path)
    agent.locate("the mug", [path])
    agent.locate("the kettle", [str(path)])
    assert len(letterboxes) == 1 and backend.sent[0] == backend.sent[1]


def test_a_file_rewritten_between_calls_is_shown_with_its_new_pixels(pixel_agent, tmp_path):
    agent, backend = pixel_agent
    path = tmp_path / "frame.png"
    first, second = wide_frames(2)
    Image.fromarray(first).save(path)
    agent.locate("the mug", [path])
    Image.fromarray(second).save(path)
    agent.locate("the mug", [path])
    assert backend.sent == [[png_of(first)], [png_of(second)]]


def test_the_center_baseline_never_letterboxes_a_frame(letterboxes):
    with GroundingAgent("center") as agent:
        result = agent.locate("my mug is to the right of the kettle", wide_frames(3))
    assert letterboxes == [] and result.pixel is not None


def test_the_memory_keeps_the_most_recent_frames_within_its_bytes():
    frames = wide_frames(3)
    one = frames[0].nbytes + 2 * 3 * 512 * 512
    memory = FrameMemory(max_bytes=2 * one)
    shown = [memory.shown(f, f"frames[{i}]", DEFAULT_PAD_COLOR) for i, f in enumerate(frames)]
    assert len(memory) == 2
    assert memory.shown(frames[2], "frames[0]", DEFAULT_PAD_COLOR) is shown[2]
    assert memory.shown(frames[0], "frames[0]", DEFAULT_PAD_COLOR) is not shown[0]
