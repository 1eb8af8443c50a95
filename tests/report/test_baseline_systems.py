"""Which systems a report shows as baselines (povagent/report/baseline_systems.py): every backend
whose plugin declares itself an offline baseline, read from its class, never from a list of
names; a model is never one."""

from __future__ import annotations

from typing import Any, ClassVar

import pytest

from povagent import hookimpl
from povagent.interfaces import Backend
from povagent.report.baseline_systems import is_baseline_system

OFFLINE = ["center", "random", "oracle", "simulated", "planted", "explorer-oracle", "explorer-random"]


@pytest.mark.parametrize("backend", OFFLINE)
def test_every_built_in_offline_backend_is_a_baseline(povagent_host, backend):
    assert is_baseline_system({"backend": backend, "strategy": "active"}, backend, povagent_host)


@pytest.mark.parametrize("backend", ["litellm", "transformers", "replay", "not-installed"])
def test_a_model_a_replayed_run_and_an_unknown_backend_are_not(povagent_host, backend):
    assert not is_baseline_system({"backend": backend, "model": "gpt-5.4"}, "gpt-5.4", povagent_host)


class Walker(Backend):
    """A third-party explorer that answers from the records."""

    offline_baseline: ClassVar[bool] = True

    def identity(self) -> dict[str, Any]:
        return {"name": "walker"}

    async def complete(self, request: Any, images: Any) -> Any:
        raise NotImplementedError


class _WalkerPlugin:
    @hookimpl
    def register_backends(self, register: Any) -> None:
        register("walker", Walker, description="walks to the ground truth (test)")


def test_a_plugin_backend_declaring_itself_an_offline_baseline_is_one_with_no_list_to_edit(povagent_host):
    name = povagent_host.add_plugin(_WalkerPlugin(), name="walker-plugin")
    try:
        assert is_baseline_system({"backend": "walker"}, "walker", povagent_host)
    finally:
        povagent_host.remove_plugin(name)
