"""A checkpoint's chat template is untrusted Jinja: rendered once at load in transformers'
sandbox; an escape, or a transformers that would show templates the live images, is one line."""

from __future__ import annotations

import shutil
from pathlib import Path

import jinja2.sandbox
import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent_plugins.backends.chat_template_check import ChatTemplateRefused, check_chat_template

pytestmark = pytest.mark.timeout(120)


def escaping_template(marker: Path) -> str:
    """A template reaching for Python's internals to run a shell command (the sandbox refuses)."""
    return "{{ cycler.__init__.__globals__.os.system('touch " + str(marker) + "') }}{% for m in messages %}{{ m['role'] }}{% endfor %}"


def test_a_chat_template_escape_stops_the_run_in_one_line_and_runs_nothing(tmp_path, mini_root, tiny_idefics3):
    folder = tmp_path / "escaping"
    shutil.copytree(tiny_idefics3, folder)
    marker = tmp_path / "escaped"
    (folder / "chat_template.jinja").write_text(escaping_template(marker))
    path = tmp_path / "run.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": str(mini_root),
        "backend": {"name": "transformers", "options": {"model": str(folder)}},
        "instances": {"conditions": ["c"], "houses": ["train_house_00000"]},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "output": str(tmp_path / "out"),
    }))
    result = CliRunner().invoke(app, ["run", str(path), "--quiet"])
    assert result.exit_code == 4, result.output
    assert "Traceback" not in result.output
    (stop,) = [line for line in result.output.splitlines() if line.startswith("stopped early:")]
    assert f"load_failed: PermanentBackendError: cannot load checkpoint {folder}: its chat template does not render a request (SecurityError" in stop
    assert (tmp_path / "out" / "results.jsonl").read_text().count("\n") == 1  # stopped after the first request
    assert not marker.exists()


class ObjectShowingProcessor:
    """A processor rendering templates the way transformers releases before plain-data rendering
    did: in the sandbox, with the conversation's objects (its decoded images) as they are."""

    def apply_chat_template(self, conversation, chat_template=None, tokenize=False, **_):
        env = jinja2.sandbox.ImmutableSandboxedEnvironment()
        return env.from_string(chat_template or "").render(messages=conversation)


def test_a_transformers_showing_templates_the_live_images_is_refused(tmp_path):
    with pytest.raises(ChatTemplateRefused, match=r"shows chat templates the decoded images themselves.*upgrade transformers"):
        check_chat_template(ObjectShowingProcessor())


def test_the_installed_transformers_shows_templates_plain_data_and_a_sound_template_passes(tiny_idefics3):
    from transformers import AutoProcessor

    check_chat_template(AutoProcessor.from_pretrained(tiny_idefics3))
