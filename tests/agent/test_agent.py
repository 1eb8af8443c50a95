"""The GroundingAgent end to end: offline baselines, a real HTTP model server on loopback, errors."""

from __future__ import annotations

import asyncio
import base64
import io
import os
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image

from povagent.agent import GroundingAgent, Localization
from povagent.answers.spec import ParseStatus
from povagent.config.retry_policy import RetryPolicy
from povagent.dataset.release_models import Condition
from povagent.errors import BadInputError, ConfigError, NoAnswerError, UnparseableAnswerError
from povagent.geometry.camera import Camera
from povagent.geometry.goals import PinholeCamera
from povagent.testing.loopback_server import Fault, LoopbackServer, Reply

FAST_RETRY = RetryPolicy(attempts=3, initial_wait=0.01, max_wait=0.05)
KEY_ENV = "POVAGENT_AGENT_TEST_KEY"


def wide_frames(n: int = 3) -> list[np.ndarray]:
    """``n`` 1280x720 RGB arrays, each a different grey."""
    return [np.full((720, 1280, 3), 40 * (i + 1), np.uint8) for i in range(n)]


@pytest.fixture
def server():
    with LoopbackServer(reply='{"selected_image": 0, "x": 256, "y": 256}', max_lifetime_s=60) as s:
        yield s


@pytest.fixture
def model_agent(server, monkeypatch):
    """An agent on the litellm backend talking to the loopback server."""
    monkeypatch.setenv(KEY_ENV, "test-key")
    agent = GroundingAgent(
        "litellm",
        backend_options={"model": "openai/loopback", "api_base": server.url, "api_key_env": KEY_ENV, "timeout": 10},
        retry=FAST_RETRY,
        timeout_s=20,
    )
    yield agent
    agent.close()


def sent_images(request) -> list[Image.Image]:
    """The images a recorded request carried, decoded."""
    out = []
    for part in request.user_parts():
        if part.get("type") == "image_url":
            url = part["image_url"]["url"]
            out.append(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))))
    return out


# -- offline baseline -----------------------------------------------------------------------------
def test_center_baseline_points_at_the_centre_of_the_original_frame():
    with GroundingAgent("center") as agent:
        loc = agent.locate("my mug is to the right of the kettle", wide_frames())
    assert isinstance(loc, Localization)
    assert loc.condition is Condition.INFERRED and loc.frame_index == 0
    assert loc.frame_size == (1280, 720)
    assert loc.pixel == (640.0, 360.0) and loc.pixel_index == (640, 360)
    assert loc.normalized == (0.5, 0.5)
    assert loc.square_point == (256.0, 256.0) and not loc.on_padding
    assert loc.status is ParseStatus.OK and loc.goal is None


def test_frames_may_be_paths_pil_images_and_arrays_of_any_size(tmp_path):
    path = tmp_path / "tall.jpg"
    Image.new("RGB", (480, 640), (1, 2, 3)).save(path)
    frames = [str(path), Image.new("RGB", (300, 200)), np.zeros((50, 70), np.uint8), np.ones((10, 10, 4), float)]
    with GroundingAgent("center") as agent:
        loc = agent.locate("the remote is on the sofa", frames)
    assert loc.frame_size == (480, 640)


def test_a_camera_gives_a_3d_goal_on_the_floor():
    camera = Camera.from_pose([0.0, 1.2, 0.0], 0.0, 30.0, fov=60.0, width=1280, height=720)
    with GroundingAgent("center") as agent:
        loc = agent.locate("the ball is in front of the sofa", wide_frames(), cameras=[camera, None, None])
    assert loc.goal is not None and loc.goal.method == "plane"
    # the centre pixel looks 30 degrees down from 1.2 m: it meets the floor 1.2 / tan(30) ahead
    assert np.allclose(loc.point_3d, [0.0, 0.0, 1.2 / np.tan(np.radians(30))])


def test_a_depth_image_gives_the_measured_point():
    pose = np.eye(4)
    camera = PinholeCamera.from_fov(pose, 60.0, 1280, 720)  # OpenCV: looks along +z
    depth = np.full((360, 640), 2.5, np.float32)
    with GroundingAgent("center") as agent:
        loc = agent.locate("x", wide_frames(1), cameras=camera, depths=depth)
    assert loc.goal.method == "depth" and np.allclose(loc.point_3d, [0.0, 0.0, 2.5])


def test_a_goal_above_the_horizon_is_reported_not_raised():
    camera = Camera.from_pose([0.0, 1.2, 0.0], 0.0, -30.0, fov=60.0, width=1280, height=720)  # looking up
    with GroundingAgent("center") as agent:
        loc = agent.locate("the clock above the door", wide_frames(1), cameras=[camera])
    assert loc.goal is None and "behind the camera" in loc.goal_error


def test_agent_from_a_pipeline_yaml(tmp_path):
    yaml_file = tmp_path / "pipeline.yaml"
    yaml_file.write_text("backend: center\nstrategy: spatial-cot\ntimeout: 5\n")
    agent = GroundingAgent.from_pipeline(yaml_file)
    try:
        assert agent.timeout_s == 5 and type(agent.strategy).__name__ == "SpatialCotStrategy"
        assert agent.locate("x", wide_frames(2)).frame_index == 0
    finally:
        agent.close()


def test_a_benchmark_pipeline_yaml_works_unchanged(tmp_path):
    yaml_file = tmp_path / "pipeline.yaml"
    yaml_file.write_text("dataset: {path: data/povbench}\noutput: runs/x\nbackend: center\nparser: json\n")
    with GroundingAgent.from_pipeline(yaml_file) as agent:
        assert agent.locate("x", wide_frames(1)).status is ParseStatus.OK


def test_a_typo_in_the_pipeline_names_the_line(tmp_path):
    yaml_file = tmp_path / "pipeline.yaml"
    yaml_file.write_text("backend: center\nstrategy: spatial_cot\n")
    with pytest.raises(ConfigError, match=r"line 2.*spatial-cot"):
        GroundingAgent.from_pipeline(yaml_file)


def test_alocate_runs_in_the_callers_event_loop():
    async def main():
        async with GroundingAgent("center") as agent:
            return await asyncio.gather(*(agent.alocate(f"s{i}", wide_frames(2)) for i in range(3)))

    results = asyncio.run(main())
    assert [r.pixel for r in results] == [(640.0, 360.0)] * 3


# -- a model over HTTP --------------------------------------------------------------------------
def test_model_sees_letterboxed_512_frames_and_the_answer_maps_back(model_agent, server):
    server.script('Looking at it... {"selected_image": 1, "x": 128, "y": 328}')
    loc = model_agent.locate("while cooking I left my phone right of the kettle", wide_frames())
    images = sent_images(server.requests[0])
    assert [im.size for im in images] == [(512, 512)] * 3
    assert images[1].getpixel((256, 5)) == (0, 0, 0)  # letterbox padding above the content
    assert images[1].getpixel((256, 256)) == (80, 80, 80)  # the frame's own grey
    assert loc.frame_index == 1
    assert loc.pixel == pytest.approx((320.0, 540.0))  # (128 / 0.4, (328 - 112) / 0.4)
    assert loc.raw_answer.startswith("Looking at it")
    assert (loc.prompt_tokens, loc.completion_tokens) == (10, 5)
    assert loc.model_latency_s > 0 and loc.latency_s >= loc.model_latency_s


def test_model_prompt_carries_the_sentence_and_frame_labels(model_agent, server):
    model_agent.locate("the cat sleeps left of the lamp", wide_frames(2))
    texts = [p["text"] for p in server.requests[0].user_parts() if p.get("type") == "text"]
    assert "Image 0:" in texts and "Image 1:" in texts
    assert any("the cat sleeps left of the lamp" in t for t in texts)


def test_observer_view_is_condition_given(model_agent, server):
    server.script('{"x": 500, "y": 256}')
    loc = model_agent.locate("the mug is on the table", observer_view=np.zeros((480, 640, 3), np.uint8))
    assert len(sent_images(server.requests[0])) == 1
    assert loc.condition is Condition.GIVEN and loc.frame_index == 0
    assert loc.pixel == pytest.approx((625.0, 240.0))  # x = 500 / 0.8, y = (256 - 64) / 0.8


def test_an_answer_on_the_padding_is_clamped_into_the_frame(model_agent, server):
    server.script('{"selected_image": 0, "x": 256, "y": 20}')  # above the content
    loc = model_agent.locate("x", wide_frames(1))
    assert loc.on_padding and loc.pixel == (640.0, 0.0)


def test_a_transient_failure_is_retried(model_agent, server):
    server.script(Fault(status=500))
    loc = model_agent.locate("x", wide_frames(1))
    assert loc.retries == 1 and server.request_count == 2


def test_no_answer_after_retries_is_a_no_answer_error(model_agent, server):
    server.script(*[Fault(status=503)] * 5)
    with pytest.raises(NoAnswerError, match="3 attempt"):
        model_agent.locate("x", wide_frames(1))
    assert server.request_count == 3


def test_a_refused_request_is_not_retried(model_agent, server):
    server.script(Fault(status=400, message="bad image"))
    with pytest.raises(NoAnswerError, match="refused"):
        model_agent.locate("x", wide_frames(1))
    assert server.request_count == 1


def test_an_unparseable_answer_carries_the_raw_text(model_agent, server):
    server.script("I am not sure where that is.")
    with pytest.raises(UnparseableAnswerError, match="no point could be read") as info:
        model_agent.locate("x", wide_frames(1))
    assert info.value.raw_answer == "I am not sure where that is."


def test_an_answer_naming_a_missing_frame_is_unparseable(model_agent, server):
    server.script('{"selected_image": 7, "x": 10, "y": 10}')
    with pytest.raises(UnparseableAnswerError, match=r"frames 0..1"):
        model_agent.locate("x", wide_frames(2))


def test_the_agent_never_hangs_past_its_timeout(model_agent, server):
    server.script(Reply('{"selected_image": 0, "x": 1, "y": 1}', delay_s=30))
    started = time.monotonic()
    with pytest.raises(NoAnswerError, match="within 1 s"):
        model_agent.locate("x", wide_frames(1), timeout_s=1.0)
    assert time.monotonic() - started < 2.5


def test_alocate_times_out_too(model_agent, server):
    server.script(Reply('{"selected_image": 0, "x": 1, "y": 1}', delay_s=30))

    async def main():
        started = time.monotonic()
        with pytest.raises(NoAnswerError):
            await model_agent.alocate("x", wide_frames(1), timeout_s=0.8)
        return time.monotonic() - started

    assert asyncio.run(main()) < 2.0


def test_model_keyword_takes_a_profile_and_brings_its_parser(server):
    # qwen3-vl-32b is served by vLLM (api_base); its profile reads answers officially
    server.script('{"selected_image": 0, "x": 500, "y": 300}')
    with GroundingAgent(model="qwen3-vl-32b", backend_options={"api_base": server.url}, retry=FAST_RETRY, timeout_s=20) as agent:
        loc = agent.locate("x", wide_frames(1))
    assert server.requests[0].body["model"] == "Qwen/Qwen3-VL-32B-Instruct"
    assert loc.status is ParseStatus.OK and loc.square_point == (500.0, 300.0)


def test_a_repair_parser_given_with_a_profile_rescales_0_1000_answers(server):
    # the model answers on 0-1000: a robot wants the repair, the profile's official reading would clamp it
    server.script('{"selected_image": 0, "x": 500, "y": 750}')
    with GroundingAgent(model="qwen3-vl-32b", parser="rescale-1000", backend_options={"api_base": server.url}, retry=FAST_RETRY, timeout_s=20) as agent:
        loc = agent.locate("x", wide_frames(1))
    assert loc.status is ParseStatus.REPAIRED and loc.square_point == (256.0, 384.0)
    assert loc.pixel == pytest.approx((640.0, 680.0))  # (256 / 0.4, (384 - 112) / 0.4)


def test_model_and_another_backend_together_are_refused():
    with pytest.raises(ValueError, match=r"model= .* or backend=, not both"):
        GroundingAgent("center", model="gpt-5.4")


def test_the_timeout_holds_while_litellm_is_imported_for_the_first_call():
    # a fresh interpreter: the first call imports litellm (seconds); the call still ends on time
    code = """
import asyncio, sys, time
import numpy as np
from povagent.agent.grounding_agent import GroundingAgent
from povagent.errors import NoAnswerError
assert "litellm" not in sys.modules
frames = [np.zeros((72, 128, 3), np.uint8)]
agent = GroundingAgent(model="openai/x", backend_options={"api_base": "http://127.0.0.1:9/v1"}, timeout_s=0.5)
async def main():
    started = time.monotonic()
    try:
        await agent.alocate("x", frames)
    except NoAnswerError:
        return time.monotonic() - started
print(round(asyncio.run(main()), 2))
started = time.monotonic()
try:
    agent.locate("x", frames)
except NoAnswerError:
    print(round(time.monotonic() - started, 2))
sys.stdout.flush()
import os
os._exit(0)  # what was measured is printed: the way out need not wait for the background import
"""
    env = {k: v for k, v in os.environ.items() if not k.startswith("LITELLM_")}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    alocate_s, locate_s = (float(v) for v in done.stdout.split())
    # budget 0.5 s; importing litellm alone takes 3 s or more here
    assert alocate_s < 1.5 and locate_s < 1.5


# -- bad input ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def center_agent():
    agent = GroundingAgent("center")
    yield agent
    agent.close()


def test_no_frames_is_bad_input(center_agent):
    with pytest.raises(BadInputError, match="no frames"):
        center_agent.locate("x", [])


def test_an_unreadable_image_is_bad_input_naming_the_frame(center_agent, tmp_path):
    broken = tmp_path / "broken.png"
    broken.write_bytes(b"not a png")
    with pytest.raises(BadInputError, match=r"frames\[1\].*broken.png"):
        center_agent.locate("x", [np.zeros((8, 8, 3), np.uint8), broken])


def test_a_missing_image_file_is_bad_input(center_agent, tmp_path):
    with pytest.raises(BadInputError, match="no such image file"):
        center_agent.locate("x", [tmp_path / "nope.png"])


def test_an_image_array_of_the_wrong_type_is_bad_input(center_agent):
    with pytest.raises(BadInputError, match="dtype uint16"):
        center_agent.locate("x", [np.zeros((8, 8, 3), np.uint16)])


def test_an_empty_sentence_is_bad_input(center_agent):
    with pytest.raises(BadInputError, match="sentence"):
        center_agent.locate("  ", wide_frames(1))


def test_cameras_must_line_up_with_the_frames(center_agent):
    with pytest.raises(BadInputError, match="2 entries for 3 image"):
        center_agent.locate("x", wide_frames(3), cameras=[None, None])


def test_a_camera_of_another_size_than_its_frame_is_bad_input(center_agent):
    with pytest.raises(BadInputError, match=r"cameras\[0\] describes a 512x512 image"):
        center_agent.locate("x", wide_frames(1), cameras=[Camera.from_pose([0, 1, 0], 0, 0)])
