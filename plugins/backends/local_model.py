"""One checkpoint loaded in this process: its processor, its model, and batched generation.

:class:`LocalModel` loads a checkpoint with ``AutoProcessor`` and
``AutoModelForImageTextToText`` (``trust_remote_code`` only when the user granted it, weights
from safetensors only), turns
requests into the model's own chat format (the processor's chat template: images where the
strategy put them, the ``Image k:`` text parts kept) and generates for several requests in one
``generate`` call, padded on the left so every prompt ends where its answer begins.

Decoding: a request's temperature decides (0: greedy; above 0: sampling at it); a request
without one follows ``sampling`` (``greedy``, the default, or ``checkpoint``: the checkpoint's
own ``generation_config``, as the authors' runner called ``generate``). ``max_tokens`` is
``max_new_tokens`` (no limit asked: :data:`UNLIMITED_MAX_NEW_TOKENS`).

Models that point with special tokens (MolmoPoint) are read by
:mod:`povagent_plugins.backends.point_reader`. Everything here is blocking and runs in the
batching queue's worker thread (:mod:`povagent_plugins.backends.local_batching`); ``torch`` and
``transformers`` are imported when a model is loaded, never when this module is imported.
"""

from __future__ import annotations

import gc
from dataclasses import dataclass
from typing import Any, Literal

from PIL import Image

from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Request, TextPart
from povagent_plugins.backends.chat_template_check import check_chat_template

Sampling = Literal["greedy", "checkpoint"]


@dataclass(frozen=True)
class LoadSettings:
    """How a checkpoint is loaded (the backend's options that concern loading)."""

    model: str
    dtype: str = "auto"
    device_map: str | dict[str, Any] | None = None
    trust_remote_code: bool = False
    attn_implementation: str | None = None
    revision: str | None = None

    def key(self) -> tuple[Any, ...]:
        """A hashable key: one loaded model per distinct key."""
        device = tuple(sorted(self.device_map.items())) if isinstance(self.device_map, dict) else self.device_map
        return (self.model, self.dtype, device, self.trust_remote_code, self.attn_implementation, self.revision)


@dataclass(frozen=True)
class Decoding:
    """What one ``generate`` call needs: requests in a batch share it (the batch's group)."""

    max_new_tokens: int | None
    temperature: float | None
    sampling: Sampling

    def generate_kwargs(self) -> dict[str, Any]:
        """Keyword arguments for ``generate`` (greedy, sampling at a temperature, or the checkpoint's)."""
        kwargs: dict[str, Any] = {} if self.max_new_tokens is None else {"max_new_tokens": self.max_new_tokens}
        if self.temperature is not None and self.temperature > 0:
            kwargs.update(do_sample=True, temperature=self.temperature)
        elif self.temperature is not None or self.sampling == "greedy":
            # top_k/top_p unset too: a checkpoint's sampling defaults must not ride along
            kwargs.update(do_sample=False, temperature=None, top_p=None, top_k=None)
        return kwargs


#: New tokens when a request sets no limit (``max_tokens: null``): ``generate``'s own default
#: (a total length of 20, prompt included) would cut every answer to nothing.
UNLIMITED_MAX_NEW_TOKENS = 4096


def decoding_of(request: Request, sampling: Sampling) -> Decoding:
    """The decoding a request asks for (its strategy's budget and temperature)."""
    gen = request.generation
    budget = gen.max_tokens if gen.max_tokens is not None else UNLIMITED_MAX_NEW_TOKENS
    return Decoding(max_new_tokens=budget, temperature=gen.temperature, sampling=sampling)


@dataclass
class Conversation:
    """A request in the chat-template form processors take, with its images decoded."""

    messages: list[dict[str, Any]]
    images: list[Image.Image]


def conversation_of(request: Request, images: ImageStore) -> Conversation:
    """``request`` as chat messages: parts in order, each image as ``{"type": "image"}``
    holding the decoded picture. Text-only system and assistant turns are plain strings (as
    chat templates expect them); user turns are lists of parts."""
    messages: list[dict[str, Any]] = []
    pictures: list[Image.Image] = []
    for message in request.messages:
        if message.role != "user" and all(isinstance(p, TextPart) for p in message.parts):
            messages.append({"role": message.role, "content": "".join(p.text for p in message.parts if isinstance(p, TextPart))})
            continue
        content: list[dict[str, Any]] = []
        for part in message.parts:
            if isinstance(part, TextPart):
                content.append({"type": "text", "text": part.text})
            elif isinstance(part, ImagePart):
                picture = images.open(part.image_hash).convert("RGB")
                pictures.append(picture)
                content.append({"type": "image", "image": picture})
            else:  # a new part type must be taught here, not silently dropped
                raise TypeError(f"cannot send message part of type {type(part).__name__}")
        messages.append({"role": message.role, "content": content})
    return Conversation(messages, pictures)


@dataclass
class Generated:
    """One request's answer: text and token counts."""

    text: str
    prompt_tokens: int
    completion_tokens: int


def is_out_of_memory(exc: BaseException) -> bool:
    """Whether ``exc`` is the device (or the host) running out of memory."""
    if type(exc).__name__ == "OutOfMemoryError" or isinstance(exc, MemoryError):
        return True
    text = str(exc).lower()
    return isinstance(exc, RuntimeError) and ("out of memory" in text or "can't allocate memory" in text)


class LocalModel:
    """A loaded processor and model; :meth:`generate` answers a batch of conversations."""

    def __init__(self, settings: LoadSettings, processor: Any, model: Any) -> None:
        self.settings = settings
        self.processor = processor
        self.model = model
        #: set once :meth:`free` ran: the model may not be used again
        self.freed = False

    @classmethod
    def load(cls, settings: LoadSettings) -> LocalModel:
        """Load the processor and the model (blocking: seconds to minutes)."""
        import torch
        from transformers import AutoModelForImageTextToText, AutoProcessor

        common: dict[str, Any] = {"trust_remote_code": settings.trust_remote_code}
        if settings.revision is not None:
            common["revision"] = settings.revision
        processor = AutoProcessor.from_pretrained(settings.model, **common)
        check_chat_template(processor)  # untrusted Jinja: refused here, not per request
        tokenizer = getattr(processor, "tokenizer", processor)
        tokenizer.padding_side = "left"  # prompts end where answers begin
        # safetensors only: a pickle (pytorch_model.bin) beside them is never torch.load-ed
        kwargs: dict[str, Any] = dict(common, use_safetensors=True)
        kwargs["dtype"] = settings.dtype if settings.dtype == "auto" else getattr(torch, settings.dtype)
        if settings.device_map is not None:
            kwargs["device_map"] = settings.device_map
        if settings.attn_implementation is not None:
            kwargs["attn_implementation"] = settings.attn_implementation
        model = AutoModelForImageTextToText.from_pretrained(settings.model, **kwargs).eval()
        if settings.device_map is None and torch.cuda.is_available():
            model = model.to("cuda")  # no placement asked for: the GPU when there is one
        return cls(settings, processor, model)

    @property
    def tokenizer(self) -> Any:
        """The processor's tokenizer."""
        return getattr(self.processor, "tokenizer", self.processor)

    def inputs(self, conversations: list[Conversation], **extra: Any) -> Any:
        """The processor's tensors for a batch (chat template applied, padded on the left)."""
        batch = [c.messages for c in conversations]
        return self.processor.apply_chat_template(
            batch, tokenize=True, add_generation_prompt=True, return_dict=True, return_tensors="pt", padding=True, **extra
        )

    def to_device(self, inputs: Any) -> dict[str, Any]:
        """Tensors moved to the model's device (other values as they are)."""
        device = self.model.device
        return {k: v.to(device) if hasattr(v, "to") else v for k, v in dict(inputs).items()}

    def generate(self, conversations: list[Conversation], decoding: Decoding) -> list[Generated]:
        """Answers for ``conversations`` from one ``generate`` call (an out-of-memory error
        is the caller's to tell apart: :func:`is_out_of_memory`)."""
        import torch

        inputs = self.to_device(self.inputs(conversations))
        with torch.inference_mode():
            output = self.model.generate(**inputs, **decoding.generate_kwargs())
        prompt_length = inputs["input_ids"].shape[1]
        new_tokens = output[:, prompt_length:]
        texts = self.tokenizer.batch_decode(new_tokens, skip_special_tokens=True, clean_up_tokenization_spaces=False)
        prompt_counts = inputs["attention_mask"].sum(dim=1).tolist()
        return [
            Generated(text, int(prompt), self.answer_length(tokens))
            for text, prompt, tokens in zip(texts, prompt_counts, new_tokens)
        ]

    def answer_length(self, tokens: Any) -> int:
        """Generated tokens up to and including the first end-of-turn (padding after it not counted)."""
        stops = self.model.generation_config.eos_token_id
        stops = set(stops if isinstance(stops, list) else [stops] if stops is not None else [])
        ids = tokens.tolist()
        for i, token in enumerate(ids):
            if token in stops:
                return i + 1
        return len(ids)

    def release_cached_memory(self) -> None:
        """Give the device's cached blocks back (after an out-of-memory, and when freed)."""
        import torch

        gc.collect()
        if torch.cuda.is_available():
            torch.cuda.empty_cache()

    def free(self) -> None:
        """Drop the model and the processor and give their memory back."""
        self.model = None
        self.processor = None
        self.freed = True
        self.release_cached_memory()
