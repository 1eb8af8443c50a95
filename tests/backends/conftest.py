"""Fixtures for backend tests: small real images in a real store, requests laid out as the
strategies lay them out ("Image i:" text part before each image), and loopback servers."""

from __future__ import annotations

import pytest
from PIL import Image

from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent.testing.loopback_server import LoopbackServer


@pytest.fixture
def store() -> ImageStore:
    """A fresh image store."""
    return ImageStore()


def labelled_request(
    store: ImageStore,
    n_images: int,
    prompt: str = "Sentence: the mug is left of the sofa.",
    generation: GenerationParams | None = None,
    instance=None,
) -> Request:
    """A request showing ``n_images`` distinct tiny images, each after its "Image i:" label."""
    parts: list = []
    for i in range(n_images):
        h = store.add_pil(Image.new("RGB", (4, 4), (i * 7 % 256, i, 255 - i))).image_hash
        parts += [TextPart(f"Image {i}:"), ImagePart(h, label=f"Image {i}:")]
    parts.append(TextPart(prompt))
    spec = (
        AnswerSpec(schema=frame_answer_schema(n_images, 512, 512), n_frames=n_images, asks_frame=True)
        if n_images > 1
        else AnswerSpec(schema=point_answer_schema(512, 512), n_frames=1, asks_frame=False)
    )
    return Request(
        messages=(Message.text("system", "You are a robot."), Message("user", tuple(parts))),
        answer=spec,
        generation=generation or GenerationParams(max_tokens=256),
        instance=instance,
    )


@pytest.fixture
def make_request(store):
    """Build a labelled request on the test's store: ``make_request(n_images, prompt=..., ...)``."""

    def build(n_images: int, **kwargs) -> Request:
        return labelled_request(store, n_images, **kwargs)

    return build


@pytest.fixture
def loopback(loopback_server) -> LoopbackServer:
    """The ``povagent.testing.pytest_plugin`` loopback server (a valid A/B answer; stops itself in 60 s)."""
    return loopback_server


@pytest.fixture
def api_key(monkeypatch) -> str:
    """A fake API key exported as POVAGENT_TEST_KEY."""
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-secret-123")
    return "sk-test-secret-123"
