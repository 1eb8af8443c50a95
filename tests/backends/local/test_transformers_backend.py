"""The in-process ``transformers`` backend on tiny real checkpoints (Idefics3, Qwen2-VL-style):
through the runner, a sweep and the GroundingAgent like any backend, batched like one at a time."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path

import pytest
import yaml
from PIL import Image

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.config.pipeline import load_pipeline
from povagent.config.remote_code import remote_code_granted
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent.run.runner import run_pipeline
from povagent_plugins.backends.transformers_backend import TransformersBackend

pytestmark = pytest.mark.timeout(120)

ONE_HOUSE = {"conditions": ["a", "c"], "houses": ["train_house_00000"], "directions": ["left"]}


def pipeline(tmp_path: Path, mini_root: Path, options: dict, name: str = "run", **extra) -> Path:
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "transformers", "options": {"max_batch": 4, **options}},
        "strategy": {"name": "basic", "options": {"max_tokens": 6}},
        "instances": ONE_HOUSE,
        "concurrency": 4,
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 60,
        "output": str(tmp_path / name),
        **extra,
    }
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def rows(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "results.jsonl").read_text().splitlines()]


def requests(store: ImageStore, n: int) -> list[Request]:
    """``n`` distinct requests showing two labelled images each."""
    out = []
    for i in range(n):
        parts: list = []
        for k in range(2):
            stored = store.add_pil(Image.new("RGB", (48, 40), (40 * i % 255, 90 * k, 30)))
            parts += [TextPart(f"Image {k}:"), ImagePart(stored.image_hash)]
        parts.append(TextPart(f"Sentence {i}: the mug is left of the sofa. Output ONLY valid JSON"))
        spec = AnswerSpec(schema=frame_answer_schema(2, 512, 512), n_frames=2, asks_frame=True)
        messages = (Message.text("system", "You are a robot."), Message("user", tuple(parts)))
        out.append(Request(messages, spec, GenerationParams(max_tokens=8)))
    return out


def trusted(**options) -> TransformersBackend:
    """A backend whose checkpoint's own code may run, granted as the Python call grants it."""
    with remote_code_granted():
        return TransformersBackend(**options)


async def answers(backend: TransformersBackend, batch: list[Request], store: ImageStore) -> list[str]:
    try:
        responses = await asyncio.gather(*(backend.complete(r, store) for r in batch))
        return [r.text for r in responses]
    finally:
        await backend.aclose()


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory, mini_root, tiny_idefics3):
    """(pipeline, its result, the checkpoints loaded while it ran): one run of the Idefics3
    checkpoint over one house, finished once for the tests that read it or resume it."""
    from povagent_plugins.backends.local_model import LocalModel

    home = tmp_path_factory.mktemp("finished")
    loads: list[str] = []
    real_load = LocalModel.load.__func__  # type: ignore[attr-defined]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(LocalModel, "load", classmethod(lambda cls, settings: loads.append(settings.model) or real_load(cls, settings)))
        path = pipeline(home, mini_root, {"model": str(tiny_idefics3)})
        result = run_pipeline(load_pipeline(path))
    return path, result, loads


def test_the_runner_evaluates_a_local_checkpoint_like_any_backend(finished_run, tiny_idefics3):
    path, result, _ = finished_run
    written = rows(path.parent / "run")
    assert len(written) == 2 and result.stats.requests == 2
    # random weights answer nonsense: a typed parse error per row, never an infra failure
    assert {r["status"] for r in written} <= {"answered", "parse_error"}
    assert all(r["model"].startswith(f"{tiny_idefics3}#") and r["backend"] == "transformers" for r in written)
    assert all(r["exchanges"][0]["completion_tokens"] >= 1 and r["exchanges"][0]["prompt_tokens"] > 10 for r in written)


def test_a_finished_run_resumes_without_loading_the_model_again(finished_run, tiny_idefics3, monkeypatch):
    from povagent_plugins.backends.local_model import LocalModel

    path, _, first_loads = finished_run
    loads: list[str] = []
    real_load = LocalModel.load.__func__  # type: ignore[attr-defined]
    monkeypatch.setattr(LocalModel, "load", classmethod(lambda cls, settings: loads.append(settings.model) or real_load(cls, settings)))
    again = run_pipeline(load_pipeline(path))
    assert again.stats.requests == 0 and len(rows(path.parent / "run")) == 2
    assert first_loads == [str(tiny_idefics3)]  # loaded once, for the first run
    assert loads == []  # and not again for the finished one


def test_a_batch_out_of_memory_is_split_and_every_row_answered(tiny_fits_two):
    store = ImageStore()
    batch = requests(store, 5)
    backend = trusted(model=str(tiny_fits_two), max_batch=8)

    async def go() -> tuple[list[str], object]:
        try:
            await backend.start()
            responses = await asyncio.gather(*(backend.complete(r, store) for r in batch))
            return [r.text for r in responses], backend.batch_stats
        finally:
            await backend.aclose()

    texts, stats = asyncio.run(go())
    assert len(texts) == 5 and stats.splits >= 2 and stats.largest <= 2


def test_a_request_that_never_fits_is_a_typed_row_not_retried(tmp_path, mini_root, tiny_fits_none):
    path = pipeline(tmp_path, mini_root, {"model": str(tiny_fits_none)}, retry={"attempts": 3, "initial_wait": 0.0, "max_wait": 0.0})
    run_pipeline(load_pipeline(path), trust_remote_code=True)
    written = rows(tmp_path / "run")
    assert [r["status"] for r in written] == ["infra_error", "infra_error"]
    assert all(r["error_type"] == "out_of_memory" and r["retries"] == 0 for r in written)


def test_batched_answers_equal_one_at_a_time_under_greedy_decoding(tiny_qwen):
    store = ImageStore()
    batch = requests(store, 6)
    alone = asyncio.run(answers(trusted(model=str(tiny_qwen), max_batch=1), batch, store))
    backend = trusted(model=str(tiny_qwen), max_batch=8)
    together = asyncio.run(_with_stats(backend, batch, store))
    assert together[0] == alone and len(set(alone)) > 1
    assert together[1] == 6  # all six in one generate call


async def _with_stats(backend: TransformersBackend, batch: list[Request], store: ImageStore) -> tuple[list[str], int]:
    try:
        # no start() first: requests that wait for the load wake together into one batch
        responses = await asyncio.gather(*(backend.complete(r, store) for r in batch))
        return [r.text for r in responses], backend.batch_stats.largest
    finally:
        await backend.aclose()


def test_the_processors_chat_template_sees_the_image_labels_in_order(tiny_idefics3):
    from povagent_plugins.backends.local_model import conversation_of

    store = ImageStore()
    (request,) = requests(store, 1)
    conversation = conversation_of(request, store)
    assert conversation.messages[0] == {"role": "system", "content": "You are a robot."}
    kinds = [p["type"] if p["type"] == "image" else p["text"][:8] for p in conversation.messages[1]["content"]]
    assert kinds == ["Image 0:", "image", "Image 1:", "image", "Sentence"] and len(conversation.images) == 2


def test_a_sweep_runs_cells_on_a_local_checkpoint(tmp_path, mini_root, tiny_qwen):
    from povagent.run.sweep import run_sweep

    base = yaml.safe_load(pipeline(tmp_path, mini_root, {"model": str(tiny_qwen)}).read_text())
    (tmp_path / "base.yaml").write_text(yaml.safe_dump(base))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(f"base: base.yaml\noutput: {tmp_path / 'sweep'}\naxes:\n  conditions: [a, c]\n")
    result = run_sweep(sweep, quiet=True, trust_remote_code=True)
    assert sorted(result.results) == ["a", "c"]
    assert all(r.stats.requests == 1 for r in result.results.values())


def test_the_grounding_agent_locates_with_a_local_checkpoint(tiny_pointing):
    from povagent.agent import GroundingAgent

    frames = [Image.new("RGB", (64, 48), (200, 10, 10)), Image.new("RGB", (64, 48), (10, 200, 10))]
    options = {"model": str(tiny_pointing)}
    with GroundingAgent(
        "transformers", backend_options=options, strategy_options={"max_tokens": 4}, timeout_s=60, trust_remote_code=True
    ) as agent:
        loc = agent.locate("my mug is left of the sofa", frames)
    # the pointing checkpoint points into the last image it was shown, half-way down
    assert loc.frame_index == 1 and loc.status.value == "ok"
    assert loc.normalized[1] == pytest.approx(0.5, abs=0.02)


def test_a_changed_checkpoint_gets_another_identity(tmp_path, tiny_idefics3):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(tiny_idefics3, copy)
    before = TransformersBackend(model=str(copy)).identity()
    weights = copy / "model.safetensors"
    data = bytearray(weights.read_bytes())
    data[-1] ^= 0xFF  # one weight changed, the header (names, shapes) the same
    weights.write_bytes(bytes(data))
    after = TransformersBackend(model=str(copy)).identity()
    assert before["checkpoint_sha256"] != after["checkpoint_sha256"] and before["model"] != after["model"]


def test_an_unknown_option_is_one_line_naming_it():
    with pytest.raises(ConfigError, match=r"backend 'transformers': option 'max_btach': unknown option"):
        TransformersBackend(model="some/model", max_btach=4)


@pytest.mark.parametrize("model", ["/no/such/checkpoint", "./typo-in-folder", "runs/a/b"])
def test_a_folder_that_does_not_exist_is_one_line_naming_the_option(model):
    with pytest.raises(ConfigError, match=r"option 'model': no folder"):
        TransformersBackend(model=model)


def test_a_profile_without_a_checkpoint_is_refused():
    with pytest.raises(ConfigError, match="no checkpoint to run in-process"):
        TransformersBackend(model="gpt-5.4")


def test_remote_code_is_not_run_unless_asked(tiny_qwen):
    store = ImageStore()
    backend = TransformersBackend(model=str(tiny_qwen))
    with pytest.raises(Exception, match=r"runs the checkpoint's own Python code.*pass --trust-remote-code"):
        asyncio.run(answers(backend, requests(store, 1), store))


def test_one_model_per_process_a_second_checkpoint_waits_for_the_first_to_close(tiny_idefics3, tiny_qwen):
    from povagent.interfaces import PermanentBackendError

    async def go() -> None:
        first = TransformersBackend(model=str(tiny_idefics3))
        second = trusted(model=str(tiny_qwen))
        await first.start()
        try:
            with pytest.raises(PermanentBackendError, match="one model per process") as refused:
                await second.start()
            assert refused.value.kind == "model_busy"
        finally:
            await first.aclose()
        await second.start()  # the first one is freed: the second loads
        await second.aclose()

    asyncio.run(go())
