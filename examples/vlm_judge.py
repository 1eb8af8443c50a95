"""A VLM surface judge: the generator's stage 3 asked of a vision-language model, as in the paper.

A plugin module like any other: it registers the judge ``vlm`` through ``register_judges``. The
judge shows the model the observer view and asks whether a small object fits in one direction of
the anchor, and on what surface. The model is called through a povagent backend (litellm by
default), so any model and any ``backend.options`` a pipeline takes work here too::

    povagent generate --out data/vlm --houses 3 --plugin examples/vlm_judge.py --judge vlm \\
        --judge-option model=gpt-5.4 --judge-option cache=data/vlm-judge.sqlite

or in a pipeline at the repository's root (a ``.py`` path is read from the YAML file's folder)::

    plugins: [examples/vlm_judge.py]
    dataset:
      generate: {houses: 3, out: data/vlm, judge: {name: vlm, options: {model: gpt-5.4}}}

Options: ``backend`` (a registered backend name, default ``litellm``), ``cache`` (a response
cache file: the same request is answered once, so a seed keeps giving the same dataset), and
every other option goes to the backend (``model``, ``api_key_env``, ``api_base``...). Nothing
here is needed offline: the default judge is ``physical-rules``.
"""

from __future__ import annotations

import asyncio
import json
import re
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from povagent import hookimpl
from povagent.geometry.directions import spec_of

PROMPT = """This photo shows a {anchor}. Imagine a small object, about 30 cm across (a book, a mug, a \
pair of boots), placed {where} the {anchor}, as seen from this viewpoint. Could it physically stand \
there, and on what surface? Answer with JSON only:
{{"verdict": "appropriate" or "inappropriate", "surface": "on the floor", "on the {anchor}", ... or null}}"""

ANSWER_SCHEMA = {
    "type": "object",
    "required": ["verdict", "surface"],
    "properties": {"verdict": {"enum": ["appropriate", "inappropriate"]}, "surface": {"type": ["string", "null"]}},
}


class VlmJudge:
    """Asks a vision-language model for each (pair, direction) verdict, temperature 0."""

    def __init__(self, backend: str = "litellm", cache: str | None = None, **backend_options: Any) -> None:
        self.backend = backend
        self.cache = cache
        self.backend_options = backend_options

    def judge(self, request):
        """The model's verdict on ``request.direction`` of ``request.anchor`` in the observer view."""
        from povagent.generate import SurfaceVerdict

        text = _run_to_completion(self._ask(request))
        match = re.search(r"\{.*\}", text, re.DOTALL)
        try:
            answer = json.loads(match.group(0)) if match else {}
        except ValueError:
            answer = {}
        surface = answer.get("surface") if isinstance(answer, dict) else None
        if answer.get("verdict") == "appropriate" and isinstance(surface, str) and surface.startswith("on "):
            return SurfaceVerdict("appropriate", surface, "the model's answer")
        return SurfaceVerdict("inappropriate", None, f"the model said: {text[:200]}")

    async def _ask(self, request) -> str:
        from PIL import Image

        from povagent.answers.spec import AnswerSpec
        from povagent.engine.cache import ResponseCache, cache_key
        from povagent.exchange.images import ImageStore
        from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
        from povagent.generate.judge import surface_noun
        from povagent.plugins import get_plugin_host

        images = ImageStore()
        view = images.add_pil(Image.fromarray(request.image))
        anchor = surface_noun(request.anchor.object_type)
        prompt = PROMPT.format(anchor=anchor, where=spec_of(request.direction).paper_words)
        question = Request(
            messages=(Message("user", (ImagePart(view.image_hash), TextPart(prompt))),),
            answer=AnswerSpec(schema=ANSWER_SCHEMA, n_frames=1, asks_frame=False),
            generation=GenerationParams(max_tokens=128, temperature=0.0),
        )
        backend = get_plugin_host().create("backend", self.backend, self.backend_options)
        cache = ResponseCache(self.cache) if self.cache else None
        key = cache_key(backend.identity(), question.content_hash(), 0)
        try:
            cached = cache.get(key) if cache else None
            if cached is not None:
                return cached.text
            response = await backend.complete(question, images)
            if cache:
                cache.put(key, response)
            return response.text
        finally:
            await backend.aclose()
            if cache:
                cache.close()


def _run_to_completion(coroutine):
    """Run ``coroutine`` whether or not this thread already runs an event loop (a pipeline
    generates its dataset from inside the runner's loop, where ``asyncio.run`` is refused)."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(coroutine)
    with ThreadPoolExecutor(max_workers=1) as thread:
        return thread.submit(asyncio.run, coroutine).result()


@hookimpl
def register_judges(register):
    """Register ``vlm``."""
    register("vlm", VlmJudge, description="asks a vision-language model through a povagent backend (example)")
