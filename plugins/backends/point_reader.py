"""The point reader: answers of models that point with special tokens (MolmoPoint-8B).

MolmoPoint-8B does not write its points as text. Its remote code (loaded with
``trust_remote_code``) constrains generation with a logits processor the model builds from the
inputs (``model.build_logit_processor_from_inputs(inputs)``) so that it emits pointing tokens
that index image patches, and it decodes them with
``model.extract_image_points(text, token_pooling, subpatch_mapping, image_sizes)``, where
``text`` is the generated text with special tokens kept (the processor's
``post_process_image_text_to_text(..., skip_special_tokens=False)``) and the three others are
the pointing metadata its processor returns beside the inputs when asked
(``apply_chat_template(..., return_pointing_metadata=True)`` adds ``metadata``). It returns a
list of points, each ``[object_id, image_num, x, y]`` with ``x``, ``y`` in pixels of that image
(``image_sizes``), or nothing. This is how the authors' runner read it.

Like the runner, the first point is the answer, written as the benchmark's JSON
(``{"selected_image": image_num, "x": x, "y": y}`` when the request showed several images,
``{"x": x, "y": y}`` for one) so the profile's parser reads it. When the model names no point
(or returns something that is not a point), the answer falls back to the generated text
(special tokens dropped), which the text parser then reads (``<points coords=...>`` text, or
the asked JSON). A model without ``extract_image_points`` never comes here.

Pointing requests are generated one at a time: the metadata's layout for a padded batch is the
model's own business and not documented, so nothing here guesses it.
"""

from __future__ import annotations

import json
import math
from typing import Any

from povagent_plugins.backends.local_model import Conversation, Decoding, Generated, LocalModel


def reads_points(model: Any) -> bool:
    """Whether ``model`` decodes its own points (has a callable ``extract_image_points``)."""
    return callable(getattr(model, "extract_image_points", None))


def point_answer(points: Any, n_images: int) -> str | None:
    """The first point of ``extract_image_points``' answer as the benchmark's JSON, or
    ``None`` when there is no well-formed point (``[object_id, image_num, x, y]``, finite)."""
    try:
        if points is None or len(points) == 0:
            return None
        _, image, x, y = (float(v) for v in list(points[0])[:4])
    except (TypeError, ValueError):
        return None
    if not all(math.isfinite(v) for v in (image, x, y)):
        return None
    if n_images > 1:
        return json.dumps({"selected_image": int(image), "x": x, "y": y})
    return json.dumps({"x": x, "y": y})


def _with_special_tokens(local: LocalModel, new_tokens: Any) -> str:
    post = getattr(local.processor, "post_process_image_text_to_text", None)
    if callable(post):
        return str(post(new_tokens, skip_special_tokens=False, clean_up_tokenization_spaces=False)[0])
    return str(local.tokenizer.batch_decode(new_tokens, skip_special_tokens=False)[0])


def read_points(local: LocalModel, conversations: list[Conversation], decoding: Decoding) -> list[Generated]:
    """Answers of a pointing model, one request at a time (see the module docstring)."""
    import torch

    model = local.model
    answers: list[Generated] = []
    for conversation in conversations:
        inputs = dict(local.inputs([conversation], return_pointing_metadata=True))
        metadata = inputs.pop("metadata", None)
        inputs = local.to_device(inputs)
        kwargs = decoding.generate_kwargs()
        build = getattr(model, "build_logit_processor_from_inputs", None)
        if callable(build):
            kwargs["logits_processor"] = build(inputs)
        with torch.inference_mode():
            output = model.generate(**inputs, **kwargs)
        new_tokens = output[:, inputs["input_ids"].shape[1] :]
        answer = None
        if isinstance(metadata, dict):
            raw = _with_special_tokens(local, new_tokens)
            points = model.extract_image_points(raw, metadata.get("token_pooling"), metadata.get("subpatch_mapping"), metadata.get("image_sizes"))
            answer = point_answer(points, len(conversation.images))
        if answer is None:
            answer = str(local.tokenizer.batch_decode(new_tokens, skip_special_tokens=True)[0])
        prompt = int(inputs["attention_mask"].sum().item())
        answers.append(Generated(answer, prompt, local.answer_length(new_tokens[0])))
    return answers
