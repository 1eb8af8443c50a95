"""Model profiles of the models the POVBench paper evaluated (``model: <name>`` in YAML).

Each profile gives the litellm model string, the parser that reads the family's answers, the
key's environment variable and the quirks seen in the paper. Self-hosted models (vLLM) need
``api_base`` in the pipeline.

``strategy_options`` carry what the authors' runner (``mimo-owl/povbench-eval``,
``evaluation/run_vlm_eval.py`` and the ablation scripts) sent each family, under the pipeline's
own strategy options (which win):

* generation: GPT ``max_completion_tokens`` 256 in every script (litellm sends ``max_tokens``
  as that for GPT-5); vLLM-served models ``max_tokens`` 256 and temperature 0; Gemini and Gemma
  no limit and no temperature (a 256 cap cuts off thinking models); models the runner ran
  locally with Transformers keep the strategy's own budget (256; CoT and S-CoT 1,024), with
  greedy decoding (temperature 0) where the runner asked for it (``do_sample=False``);
* prompts: MolmoPoint-8B and RoboPoint get the runner's own prompts for them (``prompts``).

The two rows the authors ran in-process with Transformers, ``qwen3-vl-8b-transformers`` and
``molmopoint-8b``, run in-process too (``backend="transformers"``: ``model: <name>`` loads their
``checkpoint``); named as the litellm backend's ``model`` they are the same weights behind an
OpenAI-compatible server.
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.config.profiles import ModelProfile
from povagent.dataset.release_models import Condition

_VLLM_NOTE = (
    "Self-hosted: serve with vLLM's OpenAI-compatible server started with "
    "--limit-mm-per-prompt image=30 (A/B show up to 30 images) and set api_base "
    "(e.g. http://host:8000/v1); use the litellm backend's router option to spread a sweep "
    "over several replicas."
)

#: The runner's generation settings per family (see the module docstring).
GPT_GENERATION: dict[str, Any] = {"max_tokens": 256}
VLLM_GENERATION: dict[str, Any] = {"max_tokens": 256, "temperature": 0.0}
GEMINI_GENERATION: dict[str, Any] = {"max_tokens": None}
#: Transformers with ``do_sample=False``: greedy; the budget is the strategy's (256 / 1,024).
GREEDY_LOCAL_GENERATION: dict[str, Any] = {"temperature": 0.0}

#: How the runner loaded Qwen3-VL-8B with Transformers (``torch_dtype=torch.bfloat16``,
#: ``device_map="auto"``, ``AutoProcessor.from_pretrained(model_dir)`` with no pixel limits) and
#: decoded (``generate(**inputs, max_new_tokens=...)``: the checkpoint's generation_config).
QWEN_TRANSFORMERS_LOADING: dict[str, Any] = {"dtype": "bfloat16", "device_map": "auto", "sampling": "checkpoint"}
#: How the runner loaded MolmoPoint-8B (``trust_remote_code=True``, ``dtype="auto"``,
#: ``device_map="auto"``, processor ``padding_side="left"``) and decoded (no sampling arguments).
#: Its remote code is the user's to grant (``--trust-remote-code``): the profile says it needs it.
MOLMOPOINT_LOADING: dict[str, Any] = {"dtype": "auto", "device_map": "auto", "sampling": "checkpoint"}

PAPER_PROFILES: tuple[ModelProfile, ...] = (
    ModelProfile(
        name="gpt-5.4",
        paper_name="GPT-5.4",
        litellm_model="openai/gpt-5.4",
        default_parser="official",
        api_key_env="OPENAI_API_KEY",
        # reasoning models reject sampling parameters such as temperature: drop them rather
        # than fail every request of a sweep that sets one
        backend_options={"extra": {"drop_params": True}},
        strategy_options=GPT_GENERATION,
        notes=(
            "Reasoning model: temperature is not supported (dropped); reasoning tokens count "
            "against the 256-token cap the runner set in every script (CoT included): raise "
            "max_tokens in the strategy options to give CoT room. Best on Given (0.189)."
        ),
    ),
    ModelProfile(
        name="gemini-2.5-flash",
        paper_name="Gemini-2.5-Flash",
        litellm_model="gemini/gemini-2.5-flash",
        # the paper's prompt asks for the JSON answer and the model follows it (~96% answered)
        default_parser="official",
        api_key_env="GEMINI_API_KEY",
        strategy_options=GEMINI_GENERATION,
        notes=(
            "Thinking model: thinking tokens share the output budget, so no limit is sent (as "
            "the runner); a max_tokens of 256 would cut the answer off. "
            "Unprompted, Gemini writes [{\"point\": [y, x]}] on 0-1000: keep the JSON prompt."
        ),
    ),
    ModelProfile(
        name="gemini-robotics-er",
        paper_name="Gemini-Robotics-ER",
        litellm_model="gemini/gemini-robotics-er-1.6-preview",
        # the paper reports out-of-range coordinates (Gemini's native 0-1000 convention leaks
        # into the pixel answer) and scores them clamped: parser rescale-1000 is the repair
        default_parser="official",
        api_key_env="GEMINI_API_KEY",
        strategy_options=GEMINI_GENERATION,
        notes="Produces out-of-range (0-1000) coordinates across conditions; preview model name may change.",
    ),
    ModelProfile(
        name="gemma-4",
        paper_name="Gemma-4",
        litellm_model="gemini/gemma-4-26b-a4b-it",
        default_parser="official",
        api_key_env="GEMINI_API_KEY",
        strategy_options=GEMINI_GENERATION,
        notes="Served through the Gemini API. Answered only ~40% parseably in A/B (99% in C).",
    ),
    ModelProfile(
        name="qwen3-vl-8b",
        paper_name="Qwen3-VL-8B (vLLM)",
        litellm_model="hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
        default_parser="official",
        needs_api_base=True,
        strategy_options=VLLM_GENERATION,
        notes=_VLLM_NOTE + " Follows the pixel JSON format when asked (100% answered).",
    ),
    ModelProfile(
        name="qwen3-vl-8b-transformers",
        paper_name="Qwen3-VL-8B (Transformer)",
        litellm_model="hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
        default_parser="official",
        needs_api_base=True,
        backend="transformers",
        checkpoint="Qwen/Qwen3-VL-8B-Instruct",
        checkpoint_options=QWEN_TRANSFORMERS_LOADING,
        notes=(
            "Runs in-process (backend transformers, torch + povagent[local]) as the authors' runner "
            "did: bfloat16, device_map auto, the checkpoint's own processor with its default pixel "
            "limits (the runner set no min_pixels/max_pixels), the strategy's budget (256; CoT and "
            "S-CoT 1,024) and the checkpoint's generation_config (generate was called with "
            "max_new_tokens only). Named as the litellm backend's model, the same weights behind "
            "an OpenAI-compatible server (" + _VLLM_NOTE + ")"
        ),
    ),
    ModelProfile(
        name="qwen3-vl-32b",
        paper_name="Qwen3-VL-32B (vLLM)",
        litellm_model="hosted_vllm/Qwen/Qwen3-VL-32B-Instruct",
        # answers on 0-1000 when asked for 0-511 (21% of Inferred x out of frame); the paper
        # scores them clamped: parser rescale-1000 is the repair
        default_parser="official",
        needs_api_base=True,
        strategy_options=VLLM_GENERATION,
        notes=_VLLM_NOTE + " Often answers on Qwen's native 0-1000 scale instead of pixels.",
    ),
    ModelProfile(
        name="internvl3-38b",
        paper_name="InternVL3-38B",
        litellm_model="hosted_vllm/OpenGVLab/InternVL3-38B",
        default_parser="official",
        needs_api_base=True,
        strategy_options=GREEDY_LOCAL_GENERATION,
        notes=_VLLM_NOTE + " The paper ran it 8-bit quantized. Unprompted it writes <box>[[x1,y1,x2,y2]]</box> on 0-1000.",
    ),
    ModelProfile(
        name="molmo",
        paper_name=None,
        litellm_model="hosted_vllm/allenai/Molmo-7B-D-0924",
        default_parser="molmo",
        needs_api_base=True,
        notes=(
            _VLLM_NOTE + " Writes <point x=\"..\" y=\"..\"> in percent (Molmo v1) or "
            "<points coords=...> on 0-1000 (Molmo2). The paper's MolmoPoint-8B emits special "
            "tokens instead of text: see the molmopoint-8b profile."
        ),
    ),
    ModelProfile(
        name="molmopoint-8b",
        paper_name="MolmoPoint-8B",
        litellm_model="hosted_vllm/allenai/MolmoPoint-8B",
        default_parser="molmo",
        needs_api_base=True,
        strategy_options={"prompts": "molmopoint"},
        backend="transformers",
        checkpoint="allenai/MolmoPoint-8B",
        checkpoint_options=MOLMOPOINT_LOADING,
        remote_code=True,
        notes=(
            "Runs in-process (backend transformers) with the checkpoint's own code, which only "
            "--trust-remote-code grants, as the authors' runner did: "
            "the runner's MolmoPoint prompts (task text unchanged, \"Point to the center of the "
            "target object.\"), basic strategy only; its point tokens are decoded by the model's "
            "own extract_image_points (the point reader) and the first point is answered as the "
            "benchmark's JSON; without a point the text is read (molmo parser). Behind an "
            "OpenAI-compatible server (litellm) only answers written as <points ...> text can be read."
        ),
    ),
    ModelProfile(
        name="robopoint",
        paper_name="RoboPoint",
        litellm_model="hosted_vllm/wentao-yuan/robopoint-v1-vicuna-v1.5-13b",
        default_parser="robopoint-official",
        needs_api_base=True,
        conditions=(Condition.GIVEN,),
        strategy_options={"prompts": "robopoint", **GREEDY_LOCAL_GENERATION},
        notes=(
            "Given (C) only: no valid answers with several images. Answers a list of points "
            "[(x, y), ...] as image fractions; the centroid is scored. Needs an "
            "OpenAI-compatible server in front of the LLaVA-based model."
        ),
    ),
    ModelProfile(
        name="llama-3.2-vision",
        paper_name="Llama-3.2-Vision",
        litellm_model="hosted_vllm/meta-llama/Llama-3.2-11B-Vision-Instruct",
        default_parser="official",
        needs_api_base=True,
        conditions=(Condition.GIVEN,),
        strategy_options=GREEDY_LOCAL_GENERATION,
        notes=_VLLM_NOTE + " Given (C) only: one image per prompt.",
    ),
)


@hookimpl
def register_model_profiles(register) -> None:
    """Contribute the paper's model profiles."""
    for profile in PAPER_PROFILES:
        where = f"in-process {profile.checkpoint}" if profile.backend == "transformers" else profile.litellm_model
        if profile.remote_code:  # said where the profile is listed, as its refusal says it
            where += " with its own code (--trust-remote-code)"
        register(profile.name, profile, description=f"{where} (parser {profile.default_parser})")
