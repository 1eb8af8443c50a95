"""The paper's model profiles (plugins/backends/paper_profiles.py)."""

from __future__ import annotations

import json

import pytest

from povagent.config.remote_code import remote_code_granted
from povagent.dataset.release_models import Condition
from povagent.plugins import get_plugin_host
from povagent_plugins.backends.paper_profiles import PAPER_PROFILES

PAPER_MODELS = {
    "gpt-5.4": "openai/gpt-5.4",
    "gemini-2.5-flash": "gemini/gemini-2.5-flash",
    "gemini-robotics-er": "gemini/gemini-robotics-er-1.6-preview",
    "gemma-4": "gemini/gemma-4-26b-a4b-it",
    "qwen3-vl-8b": "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
    "qwen3-vl-32b": "hosted_vllm/Qwen/Qwen3-VL-32B-Instruct",
    "internvl3-38b": "hosted_vllm/OpenGVLab/InternVL3-38B",
}


def test_paper_models_have_their_litellm_strings():
    profiles = get_plugin_host().profiles()
    assert {name: profiles[name].litellm_model for name in PAPER_MODELS} == PAPER_MODELS


@pytest.mark.parametrize("profile", PAPER_PROFILES, ids=lambda p: p.name)
def test_default_parser_is_a_registered_parser(profile):
    assert profile.default_parser in get_plugin_host().names("parser")


@pytest.mark.parametrize("profile", PAPER_PROFILES, ids=lambda p: p.name)
def test_backend_options_are_valid_litellm_backend_options(profile):
    from povagent_plugins.backends.litellm_backend import LiteLLMOptions

    LiteLLMOptions.model_validate({"model": profile.litellm_model, **profile.backend_options})


def test_paper_models_default_to_the_official_reading():
    # paper-comparable by default; repairs (rescale-1000 for 0-1000 answers, json) are opt-in
    paper = [p for p in PAPER_PROFILES if p.paper_name is not None]
    # MolmoPoint-8B's points come from its processor's special tokens officially; behind a
    # server only its <points> text can be read (molmo), so it is the one documented exception
    assert {p.name: p.default_parser for p in paper if p.default_parser != "official"} == {
        "robopoint": "robopoint-official",
        "molmopoint-8b": "molmo",
    }


def test_vllm_models_need_an_api_base():
    assert all(p.needs_api_base == p.litellm_model.startswith("hosted_vllm/") for p in PAPER_PROFILES)


def test_robopoint_answers_given_only():
    robopoint = get_plugin_host().profile("robopoint")
    assert robopoint.conditions == (Condition.GIVEN,) and robopoint.default_parser == "robopoint-official"


def test_every_profile_documents_its_quirks():
    assert all(p.notes for p in PAPER_PROFILES)


# -- what the authors' runner sent each family (run_vlm_eval.py and the ablation scripts) -------------
RUNNER_GENERATION = {
    "gpt-5.4": {"max_tokens": 256},  # max_completion_tokens=256 in every script, CoT included
    "qwen3-vl-8b": {"max_tokens": 256, "temperature": 0.0},  # vLLM: max_tokens=256, temperature=0.0
    "qwen3-vl-32b": {"max_tokens": 256, "temperature": 0.0},
    "gemini-2.5-flash": {"max_tokens": None},  # generate_content without a config: no limit
    "gemini-robotics-er": {"max_tokens": None},
    "gemma-4": {"max_tokens": None},
    "qwen3-vl-8b-transformers": {},  # Transformers: max_new_tokens 256, 1024 for ab3/ab4 (the strategies')
    "internvl3-38b": {"temperature": 0.0},  # Transformers chat, do_sample=False
    "llama-3.2-vision": {"temperature": 0.0},  # do_sample=False
    "robopoint": {"temperature": 0.0},  # do_sample=False
    "molmopoint-8b": {},  # max_new_tokens 256, the checkpoint's sampling
}


@pytest.mark.parametrize("name", sorted(RUNNER_GENERATION))
def test_profiles_carry_the_runners_generation_settings(name):
    options = get_plugin_host().profile(name).strategy_options
    assert {k: options[k] for k in ("max_tokens", "temperature") if k in options} == RUNNER_GENERATION[name]


@pytest.mark.parametrize(
    "name, strategy, max_tokens",
    [("gpt-5.4", "cot", 256), ("gemini-2.5-flash", "basic", None), ("qwen3-vl-8b-transformers", "spatial-cot", 1024),
     ("qwen3-vl-8b-transformers", "basic", 256), ("qwen3-vl-8b", "cot", 256)],
)
def test_a_profiles_budget_wins_over_the_strategys_default_and_the_pipelines_over_both(tmp_path, mini_root, name, strategy, max_tokens):
    import yaml

    from povagent.config.pipeline import load_pipeline

    path = tmp_path / "p.yaml"
    doc = {"dataset": {"path": str(mini_root)}, "model": name, "strategy": strategy, "output": str(tmp_path / "o")}
    path.write_text(yaml.safe_dump(doc))
    config = load_pipeline(path)
    built = get_plugin_host().create("strategy", config.strategy.name, config.strategy.options)
    assert built.generation.max_tokens == max_tokens
    path.write_text(yaml.safe_dump({**doc, "strategy": {"name": strategy, "options": {"max_tokens": 2048}}}))
    config = load_pipeline(path)
    assert get_plugin_host().create("strategy", config.strategy.name, config.strategy.options).generation.max_tokens == 2048


@pytest.mark.parametrize("profile", PAPER_PROFILES, ids=lambda p: p.name)
def test_strategy_options_are_valid_for_the_basic_strategy(profile):
    get_plugin_host().create("strategy", "basic", profile.strategy_options)


def test_model_specific_prompts_come_with_their_profiles():
    profiles = get_plugin_host().profiles()
    assert profiles["molmopoint-8b"].strategy_options["prompts"] == "molmopoint"
    assert profiles["robopoint"].strategy_options["prompts"] == "robopoint"
    assert all("prompts" not in p.strategy_options for n, p in profiles.items() if n not in ("molmopoint-8b", "robopoint"))


def test_molmopoint_points_map_to_a_frame_and_pixels_through_the_molmo_parser(mini_dataset):
    """``<points coords="2 1 500 250">``: image 2 counted from 1 -> frame 1; x, y on 0-1000."""
    host = get_plugin_host()
    profile = host.profile("molmopoint-8b")
    strategy = host.create("strategy", "basic", profile.strategy_options)
    parser = host.create("parser", profile.default_parser)
    inst = mini_dataset.instance("train_house_00000/0/left/a")
    spec = strategy.answer_spec(inst)
    parsed = parser.parse('<points coords="2 1 500 250">the mug</points>', spec)
    assert (parsed.selected_image, parsed.x, parsed.y) == (1, pytest.approx(256.0), pytest.approx(128.0))
    given = parser.parse('<point x="25.0" y="50.0" alt="mug">mug</point>', strategy.answer_spec(mini_dataset.instance("train_house_00000/0/left/c")))
    assert (given.x, given.y) == (pytest.approx(128.0), pytest.approx(256.0))


# -- the two rows the authors ran in-process (backend transformers) ---------------------------------
IN_PROCESS = {
    "qwen3-vl-8b-transformers": ("Qwen/Qwen3-VL-8B-Instruct", {"dtype": "bfloat16", "device_map": "auto", "sampling": "checkpoint"}),
    "molmopoint-8b": ("allenai/MolmoPoint-8B", {"dtype": "auto", "device_map": "auto", "sampling": "checkpoint"}),
}


def test_exactly_the_transformers_rows_of_the_paper_run_in_process():
    in_process = {p.name: (p.checkpoint, p.checkpoint_options) for p in PAPER_PROFILES if p.backend == "transformers"}
    assert in_process == IN_PROCESS


@pytest.mark.parametrize("name", sorted(IN_PROCESS))
def test_a_model_profile_run_in_process_resolves_to_the_transformers_backend(tmp_path, mini_root, name):
    import yaml

    from povagent.config.pipeline import load_pipeline

    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "model": name, "output": str(tmp_path / "o")}))
    config = load_pipeline(path)
    profile = get_plugin_host().profile(name)
    assert config.backend.name == "transformers" and config.parser.name == profile.default_parser
    with remote_code_granted():  # MolmoPoint's own code is the user's to grant: granted here
        backend = get_plugin_host().create("backend", config.backend.name, config.backend.options)
    checkpoint, options = IN_PROCESS[name]
    assert backend.options.model == checkpoint
    assert {k: getattr(backend.options, k) for k in options} == options
    # nothing is downloaded to name it: a Hub id not in the cache has no fingerprint yet
    assert backend.identity()["model"].startswith(checkpoint)


def test_the_transformers_backend_takes_a_profile_as_its_model_with_the_profiles_defaults(tmp_path, mini_root):
    import yaml

    from povagent.config.pipeline import load_pipeline

    path = tmp_path / "p.yaml"
    doc = {
        "dataset": {"path": str(mini_root)},
        "backend": {"name": "transformers", "options": {"model": "molmopoint-8b", "max_batch": 2}},
        "output": str(tmp_path / "o"),
    }
    path.write_text(yaml.safe_dump(doc))
    config = load_pipeline(path)
    assert config.parser.name == "molmo" and config.strategy.options["prompts"] == "molmopoint"
    with remote_code_granted():
        backend = get_plugin_host().create("backend", "transformers", config.backend.options)
    assert backend.remote_code and backend.options.max_batch == 2


def test_povagent_plugins_lists_the_in_process_profiles_and_the_backend():
    from typer.testing import CliRunner

    from povagent.cli import app

    listing = json.loads(CliRunner().invoke(app, ["plugins", "--json"]).output)
    text = json.dumps(listing)
    assert '"transformers"' in text
    for name, (checkpoint, _) in IN_PROCESS.items():
        assert name in text and f"in-process {checkpoint}" in text
