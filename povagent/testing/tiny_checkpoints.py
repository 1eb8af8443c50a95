"""Tiny vision-language checkpoints built here, for tests and benchmarks that run models in-process.

Each builder writes a complete Hugging Face folder (config, random weights, a tokenizer trained
here with ``tokenizers``, an image processor and a processor with a chat template) that
``AutoProcessor`` and ``AutoModelForImageTextToText`` load like any downloaded checkpoint. Nothing
is downloaded: the architectures are real ``transformers`` classes (Idefics3, Qwen2-VL) made
tiny (hidden size 32, one or two layers, 28-64 px images), so a folder builds in about a second
and a forward pass takes milliseconds on a CPU. The weights are random, so answers are nonsense,
but they are deterministic under greedy decoding, which is what the tests compare.

The chat templates mark the assistant's turn with ``{% generation %}`` so TRL's
``assistant_only_loss`` can train on answers only, as on a real checkpoint.

Needs ``torch`` and ``transformers`` (``pip install torch`` then ``povagent[local]``); imported
only by the tests and benchmarks that ask for it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

#: Text the tokenizer is trained on: the benchmark's prompt words, digits and JSON punctuation,
#: so a prompt tokenizes into a few hundred tokens rather than thousands of bytes.
_CORPUS = (
    "You are the intelligent brain system of a home-assistance robot. Sentence: The resident has asked "
    "the robot to retrieve an object and is describing where they last saw it. Your mission is to predict, "
    "as accurately as possible, where that object is located. Task: Select the image that best represents "
    "the scene. In the selected image, predict the center of the target object as pixel coordinates. "
    "Image coordinate system: Origin is the TOP-LEFT corner of the image. x-axis points RIGHT, y-axis "
    "points DOWN. Valid range. IMPORTANT: Output ONLY valid JSON, no other text. Point to the center of "
    'the target object. {"selected_image": 0, "x": 256, "y": 128} Image 0: Image 1: Image 2: '
    "0 1 2 3 4 5 6 7 8 9 10 100 255 511 left right front behind of the sofa bed table chair mug"
)

#: Spread of the random weights (see build_qwen2_vl).
INIT_RANGE = 0.5

#: Special tokens both tokenizers carry (the chat template's and each processor's own).
_CHAT_TOKENS = ["<|endoftext|>", "<|im_start|>", "<|im_end|>"]
_QWEN_TOKENS = ["<|vision_start|>", "<|vision_end|>", "<|image_pad|>", "<|video_pad|>"]
_IDEFICS_TOKENS = ["<fake_token_around_image>", "<image>", "<global-img>", "<end_of_utterance>"]

#: Qwen-style chat template: images where the message puts them, text parts kept verbatim, the
#: assistant's answer inside ``{% generation %}`` (TRL's assistant-only loss reads it).
QWEN_CHAT_TEMPLATE = (
    "{% macro content(message) %}{% if message['content'] is string %}{{ message['content'] }}{% else %}"
    "{% for part in message['content'] %}"
    "{% if part['type'] == 'image' %}<|vision_start|><|image_pad|><|vision_end|>"
    "{% elif part['type'] == 'text' %}{{ part['text'] }}{% endif %}{% endfor %}{% endif %}{% endmacro %}"
    "{% for message in messages %}<|im_start|>{{ message['role'] }}\n"
    "{% if message['role'] == 'assistant' %}{% generation %}{{ content(message) }}<|im_end|>{% endgeneration %}"
    "{% else %}{{ content(message) }}<|im_end|>{% endif %}\n"
    "{% endfor %}{% if add_generation_prompt %}<|im_start|>assistant\n{% endif %}"
)

#: Idefics3-style chat template (``User:`` / ``Assistant:``, ``<image>`` expanded by the processor).
IDEFICS3_CHAT_TEMPLATE = (
    "{% macro content(message) %}{% if message['content'] is string %}{{ message['content'] }}{% else %}"
    "{% for part in message['content'] %}"
    "{% if part['type'] == 'image' %}<image>{% elif part['type'] == 'text' %}{{ part['text'] }}{% endif %}"
    "{% endfor %}{% endif %}{% endmacro %}"
    "{% for message in messages %}{{ message['role'] | capitalize }}:"
    "{% if message['role'] == 'assistant' %}{% generation %}{{ content(message) }}<end_of_utterance>{% endgeneration %}"
    "{% else %}{{ content(message) }}<end_of_utterance>{% endif %}\n"
    "{% endfor %}{% if add_generation_prompt %}Assistant:{% endif %}"
)


def train_tokenizer(special: list[str], vocab_size: int = 400) -> Any:
    """A byte-level BPE tokenizer trained on :data:`_CORPUS`, wrapped for ``transformers``."""
    from tokenizers import Tokenizer, decoders, models, pre_tokenizers, trainers
    from transformers import PreTrainedTokenizerFast

    tok = Tokenizer(models.BPE())
    tok.pre_tokenizer = pre_tokenizers.ByteLevel(add_prefix_space=False)
    tok.decoder = decoders.ByteLevel()
    trainer = trainers.BpeTrainer(
        vocab_size=vocab_size, special_tokens=special, initial_alphabet=pre_tokenizers.ByteLevel.alphabet(), show_progress=False
    )
    tok.train_from_iterator([_CORPUS] * 4, trainer=trainer)
    return PreTrainedTokenizerFast(
        tokenizer_object=tok, eos_token="<|im_end|>", pad_token="<|endoftext|>", additional_special_tokens=special[1:]
    )


def _config_extras(**values: Any) -> dict[str, Any]:
    """Keyword arguments a config stores as attributes beside its declared fields."""
    return values


def _seed(seed: int) -> None:
    import torch

    torch.manual_seed(seed)


def build_qwen2_vl(folder: Path, *, seed: int = 0, layers: int = 1) -> Path:
    """A Qwen2-VL-style checkpoint in ``folder``: 28-56 px images (one to four merged patches)."""
    from transformers import Qwen2VLConfig, Qwen2VLForConditionalGeneration
    from transformers.models.qwen2_vl.image_processing_pil_qwen2_vl import Qwen2VLImageProcessorPil

    folder.mkdir(parents=True, exist_ok=True)
    tokenizer = train_tokenizer(_CHAT_TOKENS + _QWEN_TOKENS)
    tokenizer.chat_template = QWEN_CHAT_TEMPLATE
    ids = {t: tokenizer.convert_tokens_to_ids(t) for t in _CHAT_TOKENS + _QWEN_TOKENS}
    config = Qwen2VLConfig(
        text_config={
            "vocab_size": len(tokenizer),
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_hidden_layers": layers,
            "num_attention_heads": 2,
            "num_key_value_heads": 1,
            "max_position_embeddings": 4096,
            "rope_scaling": {"type": "mrope", "mrope_section": [2, 3, 3]},
            # random weights at the usual scale make a model repeat one token whatever it is
            # shown; a wider spread makes answers depend on the prompt and the images
            "initializer_range": INIT_RANGE,
            "bos_token_id": None,
            "tie_word_embeddings": True,
            "eos_token_id": ids["<|im_end|>"],
            "pad_token_id": ids["<|endoftext|>"],
        },
        vision_config={
            "depth": 1,
            "embed_dim": 32,
            "hidden_size": 32,
            "num_heads": 2,
            "mlp_ratio": 2,
            "patch_size": 14,
            "spatial_merge_size": 2,
            "temporal_patch_size": 2,
        },
        image_token_id=ids["<|image_pad|>"],
        video_token_id=ids["<|video_pad|>"],
        vision_start_token_id=ids["<|vision_start|>"],
        vision_end_token_id=ids["<|vision_end|>"],
        tie_word_embeddings=True,
        # attributes every PretrainedConfig keeps (the class's typed signature does not list them)
        **_config_extras(initializer_range=INIT_RANGE, eos_token_id=ids["<|im_end|>"], pad_token_id=ids["<|endoftext|>"]),
    )
    _seed(seed)
    model = Qwen2VLForConditionalGeneration(config).eval()
    _no_sampling(model, ids["<|im_end|>"], ids["<|endoftext|>"])
    model.save_pretrained(folder)
    image_processor = Qwen2VLImageProcessorPil(min_pixels=28 * 28, max_pixels=56 * 56, patch_size=14, merge_size=2, temporal_patch_size=2)
    _save_image_only_processor(folder, image_processor, tokenizer, QWEN_CHAT_TEMPLATE)
    return folder


def build_idefics3(folder: Path, *, seed: int = 0, layers: int = 1) -> Path:
    """An Idefics3 checkpoint in ``folder``: 32 px images, no splitting, 4 image tokens each."""
    from transformers import Idefics3Config, Idefics3ForConditionalGeneration, Idefics3Processor
    from transformers.models.idefics3.image_processing_pil_idefics3 import Idefics3ImageProcessorPil

    folder.mkdir(parents=True, exist_ok=True)
    tokenizer = train_tokenizer(_CHAT_TOKENS + _IDEFICS_TOKENS)
    tokenizer.chat_template = IDEFICS3_CHAT_TEMPLATE
    ids = {t: tokenizer.convert_tokens_to_ids(t) for t in _CHAT_TOKENS + _IDEFICS_TOKENS}
    image_size, patch, scale = 32, 8, 2
    seq_len = (image_size // patch) ** 2 // scale**2
    config = Idefics3Config(
        text_config={
            "model_type": "llama",
            "vocab_size": len(tokenizer),
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_hidden_layers": layers,
            "num_attention_heads": 2,
            "num_key_value_heads": 1,
            "max_position_embeddings": 4096,
            "initializer_range": INIT_RANGE,
            "bos_token_id": None,
            "eos_token_id": ids["<end_of_utterance>"],
            "pad_token_id": ids["<|endoftext|>"],
        },
        vision_config={
            "hidden_size": 32,
            "intermediate_size": 64,
            "num_hidden_layers": 1,
            "num_attention_heads": 2,
            "image_size": image_size,
            "patch_size": patch,
        },
        scale_factor=scale,
        image_token_id=ids["<image>"],
        **_config_extras(initializer_range=INIT_RANGE, pad_token_id=ids["<|endoftext|>"]),
    )
    _seed(seed)
    model = Idefics3ForConditionalGeneration(config).eval()
    _no_sampling(model, ids["<end_of_utterance>"], ids["<|endoftext|>"])
    model.save_pretrained(folder)
    image_processor = Idefics3ImageProcessorPil(
        do_image_splitting=False, size={"longest_edge": image_size}, max_image_size={"longest_edge": image_size}
    )
    processor = Idefics3Processor(image_processor=image_processor, tokenizer=tokenizer, image_seq_len=seq_len, chat_template=IDEFICS3_CHAT_TEMPLATE)
    processor.save_pretrained(folder)
    tokenizer.save_pretrained(folder)
    return folder


def _save_image_only_processor(folder: Path, image_processor: Any, tokenizer: Any, chat_template: str) -> None:
    """Save a Qwen2-VL processor without its video processor, as remote code in ``folder``.

    ``Qwen2VLProcessor`` insists on a video processor, which needs ``torchvision``; PyPI's
    ``torchvision`` does not load beside the CPU build of ``torch`` that tests install, so the
    folder carries a subclass taking images and text only (``image_only_processor.py``), loaded
    with ``trust_remote_code=True`` as a checkpoint's own processor is.
    """
    (folder / "image_only_processor.py").write_text(_IMAGE_ONLY_SOURCE)
    tokenizer.save_pretrained(folder)
    image_processor.save_pretrained(folder)
    auto = {"AutoProcessor": "image_only_processor.ImageOnlyQwen2VLProcessor"}
    (folder / "processor_config.json").write_text(json.dumps({"processor_class": "ImageOnlyQwen2VLProcessor", "auto_map": auto}, indent=2))
    (folder / "chat_template.jinja").write_text(chat_template)
    for name in ("tokenizer_config.json", "preprocessor_config.json"):
        doc = json.loads((folder / name).read_text())
        doc["auto_map"] = {**doc.get("auto_map", {}), **auto}
        doc["processor_class"] = "ImageOnlyQwen2VLProcessor"
        (folder / name).write_text(json.dumps(doc, indent=2))


_IMAGE_ONLY_SOURCE = '''"""Qwen2-VL's processor for images and text only (test checkpoint built by povagent.testing)."""

from transformers import Qwen2VLProcessor
from transformers.processing_utils import ProcessorMixin


class ImageOnlyQwen2VLProcessor(Qwen2VLProcessor):
    """No video processor: it needs torchvision, which the CPU test setup cannot load."""

    def __init__(self, image_processor=None, tokenizer=None, chat_template=None, **kwargs):
        self.image_token = tokenizer.image_token if hasattr(tokenizer, "image_token") else "<|image_pad|>"
        self.video_token = "<|video_pad|>"
        self.image_token_id = tokenizer.convert_tokens_to_ids(self.image_token)
        self.video_token_id = tokenizer.convert_tokens_to_ids(self.video_token)
        ProcessorMixin.__init__(self, image_processor, tokenizer, chat_template=chat_template)
'''


def add_code_leaving_a_marker(folder: Path, marker: Path, *, hang: bool = False) -> Path:
    """Name, in a checkpoint's ``config.json`` ``auto_map``, a Python file of its own that writes
    ``marker`` when it is imported: whether a checkpoint's code ran is then a file test.

    The model class it defines is the checkpoint's own architecture unchanged, so the folder
    still loads without its code (``transformers`` then uses its built-in class); ``hang``
    makes the import sleep for an hour after writing the marker (a load that never ends).
    """
    config = json.loads((folder / "config.json").read_text())
    architecture = config["architectures"][0]
    source = _MARKER_SOURCE.format(marker=str(marker), architecture=architecture, hang=hang)
    (folder / "marker_model.py").write_text(source)
    config["auto_map"] = {**config.get("auto_map", {}), "AutoModelForImageTextToText": "marker_model.MarkerModel"}
    (folder / "config.json").write_text(json.dumps(config, indent=2))
    return folder


_MARKER_SOURCE = '''"""A checkpoint's own code that leaves a marker file (test checkpoint built by povagent.testing)."""

import time
from pathlib import Path

from transformers import {architecture}

Path({marker!r}).write_text("the checkpoint's code ran")
if {hang}:
    time.sleep(3600)


class MarkerModel({architecture}):
    """The architecture unchanged: only the import above tells that this code ran."""
'''


def _no_sampling(model: Any, eos: int, pad: int) -> None:
    """A generation config that stops at the end-of-turn token and pads with the pad token."""
    model.generation_config.eos_token_id = eos
    model.generation_config.pad_token_id = pad
    model.generation_config.do_sample = False


def add_point_reader(folder: Path) -> Path:
    """Turn a :func:`build_qwen2_vl` folder into a remote-code checkpoint that, like
    MolmoPoint, exposes ``extract_image_points`` and a processor returning pointing metadata.

    The model's class is written into the folder (``pointing_model.py``) and named in the
    config's ``auto_map``, so only ``trust_remote_code=True`` loads it. Its
    ``extract_image_points(text, token_pooling, subpatch_mapping, image_sizes)`` returns one
    ``[object_id, image_num, x, y]`` point: the last image, at a place derived from the length
    of the text, half-way down, so a test knows what to expect without reading tokens.
    """
    _remote_model(folder, "pointing_model", _POINTING_SOURCE, "PointingQwen2VL")
    for name in ("processor_config.json", "preprocessor_config.json", "tokenizer_config.json"):
        doc = json.loads((folder / name).read_text())
        doc["auto_map"] = {**doc.get("auto_map", {}), "AutoProcessor": "pointing_model.PointingProcessor"}
        doc["processor_class"] = "PointingProcessor"
        (folder / name).write_text(json.dumps(doc, indent=2))
    config = json.loads((folder / "config.json").read_text())
    config["auto_map"]["AutoProcessor"] = "pointing_model.PointingProcessor"
    (folder / "config.json").write_text(json.dumps(config, indent=2))
    return folder


def add_memory_limit(folder: Path, max_rows: int) -> Path:
    """Turn a :func:`build_qwen2_vl` folder into a remote-code checkpoint whose ``generate``
    runs out of memory (``torch.OutOfMemoryError``, as CUDA raises it) for a batch of more than
    ``max_rows`` requests: out-of-memory handling is tested on a real model and a real error
    type, without a device that can run out. ``max_rows`` 0: every request runs out."""
    _remote_model(folder, "memory_limited_model", _MEMORY_LIMITED_SOURCE, "MemoryLimitedQwen2VL")
    config = json.loads((folder / "config.json").read_text())
    config["povagent_test_max_rows"] = max_rows
    (folder / "config.json").write_text(json.dumps(config, indent=2))
    return folder


def _remote_model(folder: Path, module_name: str, source: str, class_name: str) -> None:
    """Write ``source`` as ``folder/<module_name>.py`` and make its ``class_name`` (a
    ``Qwen2VLForConditionalGeneration`` subclass) the folder's model, weights kept."""
    import importlib.util

    from transformers import Qwen2VLForConditionalGeneration

    (folder / f"{module_name}.py").write_text(source)
    # the weights are saved again from the subclass: transformers maps a checkpoint's tensor
    # names by the class it knows, which a remote-code class is not
    base = Qwen2VLForConditionalGeneration.from_pretrained(folder)
    spec = importlib.util.spec_from_file_location(f"povagent_tiny_{module_name}", folder / f"{module_name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    model = getattr(module, class_name)(base.config)
    model.load_state_dict(base.state_dict())
    model.generation_config = base.generation_config
    model.save_pretrained(folder)
    config = json.loads((folder / "config.json").read_text())
    config["auto_map"] = {**config.get("auto_map", {}), "AutoModelForImageTextToText": f"{module_name}.{class_name}"}
    (folder / "config.json").write_text(json.dumps(config, indent=2))


_MEMORY_LIMITED_SOURCE = '''"""A Qwen2-VL that runs out of memory above a batch size (test checkpoint built by povagent.testing)."""

import torch
from transformers import Qwen2VLForConditionalGeneration


class MemoryLimitedQwen2VL(Qwen2VLForConditionalGeneration):
    """Raises CUDA's out-of-memory error for batches larger than config.povagent_test_max_rows."""

    def generate(self, *args, **kwargs):
        rows = kwargs["input_ids"].shape[0]
        if rows > getattr(self.config, "povagent_test_max_rows", 0):
            raise torch.OutOfMemoryError(f"CUDA out of memory. Tried to allocate a batch of {rows}")
        return super().generate(*args, **kwargs)
'''


_POINTING_SOURCE = '''"""A Qwen2-VL that points like MolmoPoint (test checkpoint built by povagent.testing)."""

from transformers import Qwen2VLForConditionalGeneration

try:  # loaded by transformers as remote code (a package) or by the builder (a file)
    from .image_only_processor import ImageOnlyQwen2VLProcessor
except ImportError:
    ImageOnlyQwen2VLProcessor = object


class PointingProcessor(ImageOnlyQwen2VLProcessor):
    """Returns ``metadata`` (pooling, sub-patch mapping, image sizes) when asked for it."""

    def apply_chat_template(self, conversation, *args, return_pointing_metadata=False, **kwargs):
        out = super().apply_chat_template(conversation, *args, **kwargs)
        if return_pointing_metadata:
            conversations = conversation if conversation and isinstance(conversation[0], list) else [conversation]
            sizes = [
                [tuple(part["image"].size) for message in conv for part in message["content"]
                 if isinstance(part, dict) and part.get("type") == "image"]
                for conv in conversations
            ]
            out["metadata"] = {"token_pooling": "pooling", "subpatch_mapping": "mapping", "image_sizes": sizes}
        return out


class PointingQwen2VL(Qwen2VLForConditionalGeneration):
    """Qwen2-VL with MolmoPoint's two extra methods."""

    def build_logit_processor_from_inputs(self, inputs):
        self.pointing_inputs_seen = sorted(inputs)
        return []

    def extract_image_points(self, text, token_pooling, subpatch_mapping, image_sizes):
        assert (token_pooling, subpatch_mapping) == ("pooling", "mapping")
        width, height = image_sizes[0][-1]
        return [[0, len(image_sizes[0]) - 1, (len(text) * 7) % width, height / 2]]
'''
