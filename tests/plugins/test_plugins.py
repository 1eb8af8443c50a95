"""The plugin host: discovery, name ownership, errors, and the lifecycle facade."""

from __future__ import annotations

import inspect
import json
import textwrap

import pytest
from typer.testing import CliRunner

from povagent import hookimpl, hookspecs
from povagent.errors import PluginError
from povagent.plugins import KIND_HOOKS, build_plugin_host, get_plugin_host


class _Scorer:
    def __init__(self, **options):
        self.options = options


def _scorer_plugin(name: str):
    class Plugin:
        @hookimpl
        def register_scorers(self, register):
            register(name, _Scorer, description="a throwaway scorer")

    return Plugin()


def _write_dist(root, dist: str, module: str, body: str, ep_name: str | None = None) -> None:
    """A minimal installed distribution: a module plus ``<dist>.dist-info`` with an entry point."""
    (root / f"{module}.py").write_text(textwrap.dedent(body))
    info = root / f"{dist}-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text(f"[povagent]\n{ep_name or dist} = {module}\n")


PLUGIN_BODY = """
from povagent import hookimpl

class Scorer:
    def score(self, instance, answer, dataset):
        return {{}}

@hookimpl
def register_scorers(register):
    register("{name}", Scorer, description="from a third-party plugin")
"""


def test_builtins_are_registered_with_their_module_as_source():
    host = build_plugin_host()
    entry = host.entry("scorer", "official")
    assert entry.source == "built-in povagent_plugins.scorers.official_scorer"
    assert entry.description


def test_every_default_plugin_loads_without_failure():
    assert build_plugin_host(strict=False).failures == []


def test_throwaway_plugin_is_registered_and_created(povagent_host):
    povagent_host.add_plugin(_scorer_plugin("tmp-scorer"), name="tmp")
    try:
        scorer = povagent_host.create("scorer", "tmp-scorer", {"alpha": 1})
        assert isinstance(scorer, _Scorer) and scorer.options == {"alpha": 1}
        assert get_plugin_host() is povagent_host
    finally:
        povagent_host.remove_plugin("tmp")
    assert "tmp-scorer" not in povagent_host.names("scorer")


def test_duplicate_name_is_an_error_naming_both_plugins(povagent_host):
    povagent_host.add_plugin(_scorer_plugin("official"), name="impostor", source="plugin impostor")
    try:
        with pytest.raises(PluginError) as err:
            povagent_host.names("scorer")
        message = str(err.value)
        assert "'official'" in message
        assert "built-in povagent_plugins.scorers.official_scorer" in message and "plugin impostor" in message
    finally:
        povagent_host.remove_plugin("impostor")


def test_unknown_name_suggests_the_nearest(povagent_host):
    with pytest.raises(PluginError, match=r"unknown scorer 'oficial' \(did you mean 'official'\?\)"):
        povagent_host.create("scorer", "oficial", {})


def test_bad_options_name_the_plugin_and_its_source(povagent_host):
    with pytest.raises(PluginError, match=r"scorer 'official' \(built-in povagent_plugins.scorers.official_scorer\) rejected its options"):
        povagent_host.create("scorer", "official", {"no_such_option": 1})


def test_entry_point_plugin_is_found(tmp_path, monkeypatch):
    _write_dist(tmp_path, "povagent-demo", "povagent_demo_plugin", PLUGIN_BODY.format(name="demo-scorer"))
    monkeypatch.syspath_prepend(str(tmp_path))
    host = build_plugin_host()
    entry = host.entry("scorer", "demo-scorer")
    assert entry.source == "entry point povagent-demo = povagent_demo_plugin from povagent-demo 1.0"


def test_entry_point_that_fails_to_import_is_reported_by_name(tmp_path, monkeypatch):
    _write_dist(tmp_path, "povagent-broken", "povagent_broken_plugin", "import no_such_module_here\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(PluginError, match=r"plugin 'povagent-broken' .*failed to load: ModuleNotFoundError: No module named 'no_such_module_here'"):
        build_plugin_host()
    lenient = build_plugin_host(strict=False)
    assert [f.plugin for f in lenient.failures] == ["povagent-broken"]


def test_config_listed_plugin_file_is_loaded(tmp_path):
    path = tmp_path / "my_plugin.py"
    path.write_text(textwrap.dedent(PLUGIN_BODY.format(name="file-scorer")))
    host = build_plugin_host([str(path)])
    assert host.entry("scorer", "file-scorer").source == f"config plugin {path}"


def test_config_listed_dotted_module_is_loaded(tmp_path, monkeypatch):
    (tmp_path / "povagent_dotted_demo.py").write_text(textwrap.dedent(PLUGIN_BODY.format(name="dotted-scorer")))
    monkeypatch.syspath_prepend(str(tmp_path))
    host = build_plugin_host(["povagent_dotted_demo"])
    assert host.entry("scorer", "dotted-scorer").source == "config plugin povagent_dotted_demo"


def test_loading_the_same_module_twice_is_harmless(tmp_path):
    path = tmp_path / "twice.py"
    path.write_text(textwrap.dedent(PLUGIN_BODY.format(name="twice-scorer")))
    host = build_plugin_host([str(path), str(path)])
    assert host.names("scorer").count("twice-scorer") == 1


def test_hook_implementation_without_spec_is_reported(tmp_path):
    path = tmp_path / "typo_plugin.py"
    path.write_text("from povagent import hookimpl\n\n@hookimpl\ndef register_scorer(register):\n    pass\n")
    with pytest.raises(PluginError, match=r"typo_plugin.py.*register_scorer"):
        build_plugin_host([str(path)])


def test_register_hook_raising_is_reported_with_its_plugin(povagent_host):
    class Broken:
        @hookimpl
        def register_parsers(self, register):
            raise RuntimeError("boom")

    povagent_host.add_plugin(Broken(), name="broken-parsers", source="plugin broken-parsers")
    try:
        with pytest.raises(PluginError, match=r"plugin broken-parsers: register_parsers raised RuntimeError: boom"):
            povagent_host.names("parser")
    finally:
        povagent_host.remove_plugin("broken-parsers")


def test_lifecycle_observer_that_raises_does_not_silence_others(povagent_host):
    seen, errors = [], []

    class Good:
        @hookimpl
        def povagent_run_end(self, run_dir, summary):
            seen.append((run_dir, dict(summary)))

    class Bad:
        @hookimpl
        def povagent_run_end(self, run_dir, summary):
            raise ValueError("observer bug")

    povagent_host.add_plugin(Good(), name="good")
    povagent_host.add_plugin(Bad(), name="bad")
    povagent_host.hooks.on_error = lambda hook, plugin, exc: errors.append((hook, plugin, str(exc)))
    try:
        povagent_host.hooks.run_end("runs/x", {"n": 1})
    finally:
        povagent_host.remove_plugin("good")
        povagent_host.remove_plugin("bad")
    assert seen == [("runs/x", {"n": 1})]
    assert errors == [("povagent_run_end", "bad", "observer bug")]


def test_every_hookspec_is_documented_and_reachable_through_the_host():
    specs = [n for n, f in inspect.getmembers(hookspecs, inspect.isfunction) if hasattr(f, "povagent_spec")]
    assert specs, "no hookspecs found"
    lifecycle = {"povagent_run_start": "run_start", "povagent_instance_done": "instance_done", "povagent_run_end": "run_end"}
    from povagent.plugins import OBJECT_HOOKS, TOOL_HOOK, LifecycleHooks

    for name in specs:
        assert inspect.getdoc(getattr(hookspecs, name)), f"{name} has no docstring"
        if name in lifecycle:
            facade = getattr(LifecycleHooks, lifecycle[name])
            spec_params = list(inspect.signature(getattr(hookspecs, name)).parameters)
            assert list(inspect.signature(facade).parameters)[1:] == spec_params
        else:
            assert name in KIND_HOOKS.values() or name in OBJECT_HOOKS.values() or name == TOOL_HOOK


def test_plugins_command_lists_every_kind_with_its_source():
    from povagent.cli import app

    result = CliRunner().invoke(app, ["plugins", "--json"])
    assert result.exit_code == 0, result.output
    listing = json.loads(result.output)
    assert {"backend", "strategy", "parser", "scorer", "judge", "profile", "failures"} <= set(listing)
    official = [e for e in listing["scorer"] if e["name"] == "official"]
    assert official and official[0]["source"] == "built-in povagent_plugins.scorers.official_scorer"
    rules = [e for e in listing["judge"] if e["name"] == "physical-rules"]
    assert rules and rules[0]["source"] == "built-in povagent_plugins.judges.physical_rules"


def test_plugins_json_lists_formats_and_answer_types_beside_the_other_kinds():
    from povagent.cli import app

    listing = json.loads(CliRunner().invoke(app, ["plugins", "--json"]).output)
    assert {e["name"] for e in listing["answer_type"]} >= {"point", "choice"}
    formats = {e["name"]: e for e in listing["format"]}
    assert set(formats) >= {"povbench", "generated", "realworld", "viewspatial", "mindcube", "3dsrbench"}
    assert formats["mindcube"] == {
        "name": "mindcube", "source": "built-in povagent_plugins.formats.mindcube",
        "description": "MindCube: multiple-choice spatial reasoning from a few views of one scene",
        "answer_type": "choice", "official_parser": "mindcube-official", "official_scorer": "choice-mindcube",
        "upstream": "mll-lab-nu/MindCube@6d8fd9acdf5b80769373a21cdbfcf068ab356e0f", "licence": "see the dataset card (the code is MIT)",
    }  # fmt: skip


def test_every_contribution_hook_has_a_builtin_plugin_using_it():
    from povagent.plugins import KINDS, OBJECT_HOOKS

    host = build_plugin_host()
    assert {kind: bool(host.names(kind)) for kind in (*KINDS, *OBJECT_HOOKS)} == dict.fromkeys((*KINDS, *OBJECT_HOOKS), True)


def test_rejected_options_never_show_a_secret(povagent_host):
    with pytest.raises(PluginError) as err:
        povagent_host.create("scorer", "official", {"api_key": "sk-proj-ABCDEF1234567890"})
    assert "ABCDEF1234567890" not in str(err.value) and "'api_key': '[REDACTED]'" in str(err.value)


def test_every_hookspec_has_a_test_plugin_implementing_it():
    """The plugin surface cannot grow a hook that no test exercises: some test module under
    ``tests/`` implements each hookspec in a throwaway plugin."""
    from pathlib import Path

    specs = [n for n, f in inspect.getmembers(hookspecs, inspect.isfunction) if hasattr(f, "povagent_spec")]
    sources = [p.read_text(encoding="utf-8") for p in Path(__file__).resolve().parents[1].rglob("*.py")]
    untested = [name for name in specs if not any(f"def {name}(" in text for text in sources)]
    assert not untested, f"hookspecs no test implements: {untested}"
