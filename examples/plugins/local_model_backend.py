"""A backend plugin wrapping a local model: no server, no API key, no download.

``BrightestSpotModel`` stands in for a local VLM. A real one would load its weights in its
constructor and run on a GPU; this one looks at the images it is given and points at the
brightest pixel of the brightest image, so the plugin runs anywhere. The backend,
``local-brightest``, turns a :class:`Request` into the model's inputs (the prompt text and the
decoded images) and the model's point into the JSON answer the request asked for.

How it reports failures, which the runner's retry rule reads:

* the device is busy (another process holds the GPU): :class:`TransientBackendError`; the runner
  waits and tries again, up to the pipeline's ``retry.attempts``, and counts the retries in
  the row;
* more images than the model takes (``max_images``): :class:`PermanentBackendError`; no retry
  can help, so the key becomes an ``infra_error`` row at once, ``error_type`` its ``kind``.

In a pipeline YAML::

    plugins: [local_model_backend.py]
    backend: {name: local-brightest, options: {max_images: 8}}
    concurrency: 1                # one model on one device: one request at a time

``busy_every: N`` makes every N-th call find the device busy, to watch a retry happen.
"""

import asyncio
import json

import numpy as np
from PIL import Image

from povagent import hookimpl
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import Request, Response, TextPart, Usage
from povagent.interfaces import Backend, PermanentBackendError, TransientBackendError


class DeviceBusy(RuntimeError):
    """The model's device is held by someone else for now."""


class TooManyImages(ValueError):
    """The model takes at most ``max_images`` images per prompt."""


class BrightestSpotModel:
    """The stand-in model: ``point(prompt, images) -> (image index, x, y)``."""

    name = "brightest-spot-v1"

    def __init__(self, max_images: int, busy_every: int = 0) -> None:
        self.max_images = max_images
        self.busy_every = busy_every
        self.calls = 0

    def point(self, prompt: str, images: list[Image.Image]) -> tuple[int, float, float]:
        """The brightest pixel of the brightest image (a real model would read the prompt)."""
        if len(images) > self.max_images:
            raise TooManyImages(f"{len(images)} images, the model takes at most {self.max_images}")
        self.calls += 1
        if self.busy_every and self.calls % self.busy_every == 0:
            raise DeviceBusy("the GPU is in use by another process")
        grey = [np.asarray(im.convert("L"), dtype=np.float32) for im in images]
        k = int(np.argmax([g.mean() for g in grey]))
        y, x = np.unravel_index(int(np.argmax(grey[k])), grey[k].shape)
        return k, float(x), float(y)


class LocalModelBackend(Backend):
    """Answers with :class:`BrightestSpotModel`, run in a worker thread."""

    def __init__(self, max_images: int = 8, busy_every: int = 0) -> None:
        if isinstance(max_images, bool) or not isinstance(max_images, int) or max_images < 1:
            raise ValueError(f"max_images must be a positive integer, got {max_images!r}")
        self.model = BrightestSpotModel(max_images, busy_every)

    def identity(self):
        """What changes the answers: the model and how many images it takes."""
        return {"backend": "local-brightest", "model": self.model.name, "max_images": self.model.max_images}

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """The model's point as the JSON answer the request asks for."""
        prompt = "\n".join(p.text for m in request.messages for p in m.parts if isinstance(p, TextPart))
        pictures = [images.open(h) for h in request.image_hashes()]
        try:
            # In a thread: a model that computes for seconds must not stop the event loop.
            k, x, y = await asyncio.to_thread(self.model.point, prompt, pictures)
        except DeviceBusy as exc:
            raise TransientBackendError(str(exc), kind="device_busy") from exc
        except TooManyImages as exc:
            raise PermanentBackendError(str(exc), kind="too_many_images") from exc
        answer = {"selected_image": k, "x": x, "y": y} if request.answer.asks_frame else {"x": x, "y": y}
        return Response(text=json.dumps(answer), usage=Usage(prompt_tokens=None, completion_tokens=None, cost_usd=0.0), model=self.model.name)


@hookimpl
def register_backends(register):
    """Contribute the local-brightest backend."""
    register("local-brightest", LocalModelBackend, description="A local model in-process (stand-in: the brightest spot)")
