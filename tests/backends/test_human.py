"""The ``human`` backend: a person named as a system, who answers only under ``povagent annotate``."""

from __future__ import annotations

import pytest
import yaml

from povagent.errors import ConfigError
from povagent.plugins import get_plugin_host


def test_a_person_is_named_human_colon_their_name():
    backend = get_plugin_host().backend("human", {"annotator": "alice"})
    assert backend.identity()["model"] == "human:alice"
    assert backend.cacheable is False


@pytest.mark.parametrize("name", ["", "a b", "../x", "x" * 65, 3])
def test_an_annotator_that_is_no_name_is_refused(name):
    with pytest.raises(ConfigError, match="annotator"):
        get_plugin_host().backend("human", {"annotator": name})


def test_a_plain_run_with_a_human_backend_stops_at_once_and_says_to_annotate(tmp_path, mini_root):
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)}, "backend": {"name": "human", "options": {"annotator": "alice"}},
        "strategy": "basic", "parser": "json", "output": str(tmp_path / "run"), "instances": {"limit": 2},
    }))  # fmt: skip
    result = run_pipeline(load_pipeline(path))
    assert result.stopped is not None and "povagent annotate" in result.stopped
    assert result.n_missing == 1  # nothing else was asked


def test_a_person_is_a_system_of_the_report_not_a_baseline(povagent_host):
    from povagent.report.baseline_systems import is_baseline_system

    assert not is_baseline_system({"backend": "human", "model": "human:alice"}, "human:alice", povagent_host)
