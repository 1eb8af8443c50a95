"""The typed seam: ``host.backend/strategy/parser/scorer`` return the interfaces' types."""

from __future__ import annotations

import typing

import pytest

from povagent import hookimpl
from povagent.errors import PluginError
from povagent.interfaces import Backend, Parser, Scorer, Strategy
from povagent.plugins import PluginHost, build_plugin_host


@pytest.mark.parametrize(("method", "interface"), [("backend", Backend), ("strategy", Strategy), ("parser", Parser), ("scorer", Scorer)])
def test_each_kind_is_made_through_a_method_typed_with_its_interface(method, interface):
    hints = typing.get_type_hints(getattr(PluginHost, method))
    assert hints["return"] is interface


@pytest.mark.parametrize(
    ("method", "name", "interface"),
    [("backend", "center", Backend), ("strategy", "basic", Strategy), ("parser", "json", Parser), ("scorer", "official", Scorer)],
)
def test_a_builtin_is_made_as_its_interface(method, name, interface):
    assert isinstance(getattr(build_plugin_host(), method)(name, {}), interface)


class _NotAScorer:
    def score(self, instance, answer, dataset):
        return {}


class _LooseScorers:
    @hookimpl
    def register_scorers(self, register):
        register("loose", _NotAScorer, description="returns no Scorer")


def test_a_factory_that_makes_no_instance_of_its_interface_is_named_with_its_source(povagent_host):
    povagent_host.add_plugin(_LooseScorers(), name="loose-scorers", source="plugin loose-scorers")
    try:
        with pytest.raises(PluginError, match=r"scorer 'loose' \(plugin loose-scorers\) made a _NotAScorer, not a Scorer"):
            povagent_host.scorer("loose")
    finally:
        povagent_host.remove_plugin("loose-scorers")
