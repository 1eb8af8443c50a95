"""A checkpoint's own code runs only when the command line or the Python call grants it: a YAML,
a mapping given as a pipeline and a model profile cannot, and a granted Hub checkpoint's code is
pinned to a commit. (The marker-file proofs on a real checkpoint are in
tests/backends/local/test_remote_code_grant.py.)"""

from __future__ import annotations

import pytest
import yaml
from pydantic import ValidationError
from typer.testing import CliRunner

from povagent.agent import GroundingAgent
from povagent.cli import app
from povagent.config.pipeline import load_pipeline
from povagent.config.profiles import ModelProfile
from povagent.config.remote_code import remote_code_allowed, remote_code_granted
from povagent.errors import ConfigError
from povagent_plugins.backends.transformers_backend import TransformersBackend

MOLMO_COMMIT = "0123456789abcdef0123456789abcdef01234567"  # a commit-shaped revision; nothing is fetched


def pipeline(tmp_path, mini_root, options: dict | None = None, **top) -> str:
    doc = {"dataset": str(mini_root), "output": str(tmp_path / "out"), **top}
    if options is not None:
        doc["backend"] = {"name": "transformers", "options": options}
    path = tmp_path / "run.yaml"
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def test_a_yaml_setting_trust_remote_code_is_refused_at_load_naming_the_flag(tmp_path, mini_root):
    path = pipeline(tmp_path, mini_root, {"model": str(tmp_path), "trust_remote_code": True})
    with pytest.raises(ConfigError) as err:
        load_pipeline(path)
    line = str(err.value).splitlines()[-1]
    assert line.startswith(f"{path}, line ") and "backend.options.trust_remote_code: " in line
    assert "--trust-remote-code" in line


def test_a_yaml_saying_trust_remote_code_false_still_loads(tmp_path, mini_root):
    (tmp_path / "ckpt").mkdir()
    config = load_pipeline(pipeline(tmp_path, mini_root, {"model": str(tmp_path / "ckpt"), "trust_remote_code": False}))
    assert config.backend.options["trust_remote_code"] is False


def test_a_mapping_given_as_a_pipeline_cannot_grant_remote_code_either(tmp_path):
    with pytest.raises(ConfigError, match="--trust-remote-code"):
        GroundingAgent.from_pipeline({"backend": {"name": "transformers", "options": {"model": str(tmp_path), "trust_remote_code": True}}})


def test_a_backend_made_in_python_cannot_take_the_grant_as_an_option(tmp_path):
    with pytest.raises(ConfigError, match="--trust-remote-code"):
        TransformersBackend(model=str(tmp_path), trust_remote_code=True)


def test_a_profile_cannot_carry_trust_remote_code():
    with pytest.raises(ValidationError, match="cannot grant trust_remote_code"):
        ModelProfile(name="p", litellm_model="x/y", backend="transformers", checkpoint="o/m", checkpoint_options={"trust_remote_code": True})


def test_a_profile_needing_remote_code_pins_a_commit_if_it_pins_anything():
    with pytest.raises(ValidationError, match="commit hash"):
        ModelProfile(name="p", litellm_model="x/y", backend="transformers", checkpoint="o/m", remote_code=True, checkpoint_options={"revision": "main"})


def test_the_molmopoint_profile_says_in_one_line_that_it_needs_the_flag(tmp_path, mini_root):
    result = CliRunner().invoke(app, ["run", pipeline(tmp_path, mini_root, model="molmopoint-8b")])
    message = str(result.exception)
    assert isinstance(result.exception, ConfigError) and "\n" not in message
    assert "'molmopoint-8b' (allenai/MolmoPoint-8B) runs the checkpoint's own Python code" in message
    assert "pass --trust-remote-code" in message and "revision" in message
    assert not (tmp_path / "out" / "results.jsonl").exists()


def test_the_molmopoint_profile_shows_the_revision_pinned_beside_the_flag(tmp_path, mini_root):
    path = pipeline(tmp_path, mini_root, {"model": "molmopoint-8b", "revision": MOLMO_COMMIT})
    result = CliRunner().invoke(app, ["run", path])
    assert f"(revision {MOLMO_COMMIT}): pass --trust-remote-code" in str(result.exception)


@pytest.mark.parametrize("revision", ["main", "refs/pr/1", MOLMO_COMMIT[:12]])
def test_a_granted_hub_checkpoint_at_a_branch_or_ref_is_refused(revision):
    with remote_code_granted(), pytest.raises(ConfigError, match="not a commit hash"):
        TransformersBackend(model="allenai/MolmoPoint-8B", revision=revision)


def test_a_granted_hub_checkpoint_pinned_to_a_commit_is_made_with_the_grant():
    with remote_code_granted():
        backend = TransformersBackend(model="molmopoint-8b", revision=MOLMO_COMMIT)
    assert backend.remote_code and backend.identity()["trust_remote_code"] is True


def test_the_grant_ends_with_the_block_that_gave_it():
    with remote_code_granted():
        assert remote_code_allowed()
    assert not remote_code_allowed()
