"""Surface judges are plugins: registered by name through ``register_judges``, chosen by name."""

from __future__ import annotations

import json
import pickle
import textwrap
from pathlib import Path

import numpy as np
import pytest

from povagent import hookimpl
from povagent.errors import ConfigError, PluginError
from povagent.generate import JudgeRequest, PhysicalRulesJudge, SurfaceVerdict, generate_dataset
from povagent.generate.judge import DEFAULT_JUDGE, RegisteredJudge, create_judge

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


class FrontOnly:
    """A throwaway judge: a target fits in front of every anchor, nowhere else."""

    def __init__(self, **options):
        self.options = options

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        if request.direction == "front":
            return SurfaceVerdict("appropriate", "on the floor")
        return SurfaceVerdict("inappropriate", None)


class FrontAndUp(FrontOnly):
    """Front and up: a pair keeps only with two directions, so these are what a dataset gets."""

    def judge(self, request: JudgeRequest) -> SurfaceVerdict:
        if request.direction == "up":
            return SurfaceVerdict("appropriate", "on the anchor")
        return super().judge(request)


def _judge_plugin(name: str, factory):
    class Plugin:
        @hookimpl
        def register_judges(self, register):
            register(name, factory, description="a throwaway judge")

    return Plugin()


def _placements(root: Path) -> list[set[str]]:
    entries = json.loads((root / "artifacts/train_house_00000/train_house_00000.json").read_text())
    return [set(e["placements"]) for e in entries]


def test_the_rules_judge_is_a_builtin_plugin_and_the_default(povagent_host):
    entry = povagent_host.entry("judge", DEFAULT_JUDGE)
    assert entry.source == "built-in povagent_plugins.judges.physical_rules" and entry.description
    assert isinstance(create_judge(DEFAULT_JUDGE), PhysicalRulesJudge)


def test_a_throwaway_judge_plugin_decides_which_directions_a_generated_dataset_has(povagent_host, tmp_path):
    povagent_host.add_plugin(_judge_plugin("front-and-up", FrontAndUp), name="tmp-judges")
    try:
        generate_dataset(tmp_path, houses=1, seed=7, frames=3, progress=False, judge="front-and-up")
    finally:
        povagent_host.remove_plugin("tmp-judges")
    placements = _placements(tmp_path)
    assert placements and all(p == {"front", "up"} for p in placements)
    assert json.loads((tmp_path / "meta.json").read_text())["generator"]["judge"] == "front-and-up"


def test_a_judge_name_registered_twice_is_an_error_naming_both_plugins(povagent_host):
    povagent_host.add_plugin(_judge_plugin(DEFAULT_JUDGE, FrontOnly), name="impostor", source="plugin impostor")
    try:
        with pytest.raises(PluginError) as err:
            povagent_host.names("judge")
    finally:
        povagent_host.remove_plugin("impostor")
    message = str(err.value)
    assert "judge name 'physical-rules' is registered twice" in message
    assert "built-in povagent_plugins.judges.physical_rules" in message and "plugin impostor" in message


def test_an_unknown_judge_name_suggests_the_nearest_and_writes_nothing(tmp_path):
    out = tmp_path / "data"
    with pytest.raises(PluginError, match=r"unknown judge 'physcal-rules' \(did you mean 'physical-rules'\?\)"):
        generate_dataset(out, houses=1, seed=0, frames=1, progress=False, judge="physcal-rules")
    assert not out.exists()


def test_options_a_judge_rejects_are_an_error_before_any_work(tmp_path):
    with pytest.raises(PluginError, match=r"judge 'physical-rules' .* rejected its options"):
        generate_dataset(tmp_path / "data", houses=1, seed=0, frames=1, judge_options={"model": "x"})
    assert not (tmp_path / "data").exists()


def test_a_factory_that_makes_no_judge_is_reported_with_its_plugin(povagent_host):
    povagent_host.add_plugin(_judge_plugin("not-a-judge", dict), name="bad-judges", source="plugin bad-judges")
    try:
        with pytest.raises(PluginError, match=r"judge 'not-a-judge' \(plugin bad-judges\) made a dict"):
            create_judge("not-a-judge")
    finally:
        povagent_host.remove_plugin("bad-judges")


def test_a_registered_judge_travels_to_worker_processes_by_name_not_by_object(povagent_host):
    povagent_host.add_plugin(_judge_plugin("front-only", FrontOnly), name="tmp-judges")
    try:
        chosen = RegisteredJudge("front-only", {"strictness": 2})
        made = chosen.resolve()
        assert isinstance(made, FrontOnly) and made.options == {"strictness": 2}
        copy = pickle.loads(pickle.dumps(chosen))
        assert copy._judge is None and (copy.name, copy.options) == ("front-only", {"strictness": 2})
        assert isinstance(copy.resolve(), FrontOnly) and copy.resolve() is not made
    finally:
        povagent_host.remove_plugin("tmp-judges")


# -- the pipeline's generator spec ----------------------------------------------------------------
PIPELINE = """\
plugins: [{plugin}]
dataset:
  generate:
    houses: 1
    frames: 2
    seed: 3
    out: {out}
    judge: {judge}
backend: center
output: {out}-run
"""

JUDGE_MODULE = """
from povagent import hookimpl
from povagent.generate import SurfaceVerdict

class FrontAndUp:
    def judge(self, request):
        if request.direction in ("front", "up"):
            return SurfaceVerdict("appropriate", "on the floor" if request.direction == "front" else "on the anchor")
        return SurfaceVerdict("inappropriate", None)

@hookimpl
def register_judges(register):
    register("front-and-up", FrontAndUp)
"""


def _pipeline(tmp_path: Path, judge: str) -> Path:
    plugin = tmp_path / "pipeline_judges.py"
    plugin.write_text(textwrap.dedent(JUDGE_MODULE))
    path = tmp_path / "pipeline.yaml"
    path.write_text(PIPELINE.format(plugin=plugin, out=tmp_path / "gen", judge=judge))
    return path


def test_a_pipeline_names_a_judge_its_plugins_register_and_the_dataset_is_generated_with_it(tmp_path):
    from povagent.config.pipeline import load_pipeline
    from povagent.run.pending import prepare_dataset

    config = load_pipeline(_pipeline(tmp_path, "front-and-up"))
    assert config.dataset.generate.judge.name == "front-and-up"
    prepare_dataset(config)
    assert json.loads((tmp_path / "gen" / "meta.json").read_text())["generator"]["judge"] == "front-and-up"
    placements = _placements(tmp_path / "gen")
    assert placements and all(p == {"front", "up"} for p in placements)


def test_a_typo_in_a_pipelines_judge_fails_before_any_work_with_line_and_nearest_name(tmp_path):
    from povagent.config.pipeline import load_pipeline

    path = _pipeline(tmp_path, "{name: front-and-upp, options: {}}")
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    assert f"{path}, line 8: dataset.generate.judge.name: unknown judge 'front-and-upp' (did you mean 'front-and-up'?)" in str(err.value)
    assert not (tmp_path / "gen").exists()


def test_the_judge_defaults_are_one_name_everywhere():
    from typer.main import get_command

    from povagent.cli import app
    from povagent.config.models import GenerateSpec

    assert GenerateSpec(out="x").judge.name == DEFAULT_JUDGE
    generate = get_command(app).commands["generate"]
    assert next(p.default for p in generate.params if p.name == "judge") == DEFAULT_JUDGE


# -- the VLM judge example --------------------------------------------------------------------------
@pytest.fixture
def vlm_judge(povagent_host, queued_backend):
    """The example's ``vlm`` judge, loaded as a pipeline lists it, answering through the queued
    test backend."""
    from povagent.plugins import get_plugin_host

    get_plugin_host([str(EXAMPLES / "vlm_judge.py")])  # the test's host loads the module
    return create_judge("vlm", {"backend": "queued"}), queued_backend


def _request(tiny_dataset, direction: str) -> JudgeRequest:
    from povagent.geometry.camera import Camera

    house = tiny_dataset.built.house
    anchor = next(o for o in house.objects if o.object_type == "Sofa")
    observer = next(o for o in house.objects if o is not anchor and o.object_type != "Doorway")
    camera = Camera(observer.center, 0.0, 0.0, 100.0, 512, 512)  # the VLM judge looks at the image only
    return JudgeRequest(house, observer, anchor, camera, direction, np.zeros((512, 512, 3), np.uint8))


def test_the_example_vlm_judge_shows_the_model_the_observer_view_and_reads_its_verdict(vlm_judge, tiny_dataset):
    judge, backend = vlm_judge
    backend.replies.append('Sure: {"verdict": "appropriate", "surface": "on the floor"}')
    verdict = judge.judge(_request(tiny_dataset, "left"))
    assert verdict == SurfaceVerdict("appropriate", "on the floor", "the model's answer")
    (sent,) = backend.requests
    assert len(sent.image_hashes()) == 1 and "to the left of" in sent.messages[0].parts[1].text


def test_the_example_vlm_judge_counts_an_unreadable_answer_as_inappropriate(vlm_judge, tiny_dataset):
    judge, backend = vlm_judge
    backend.replies.append("I cannot tell from this picture.")
    assert not judge.judge(_request(tiny_dataset, "up")).appropriate
