"""Dataset formats are registered (``register_dataset_formats``) like answer types: a key belongs
to one plugin, the host hands back the :class:`DatasetFormat` it registered, and something that
is not one (or is registered under another key) is refused naming the plugin."""

from __future__ import annotations

from pathlib import Path

import pytest

from povagent import hookimpl
from povagent.dataset.formats import DatasetFormat, DocsRow, FormatRead, PromptProfile, registered_format, registered_formats
from povagent.dataset.problems import Problem
from povagent.errors import DatasetError, PluginError


class _Loaded:
    def __init__(self, root: Path, problems: list[Problem]) -> None:
        self.root = root
        self.problems = problems


def _read(request: FormatRead) -> _Loaded:
    if not request.path.is_file():
        raise DatasetError(f"{request.path}: not found")
    return _Loaded(request.path.parent, [Problem(str(request.path), "record 3", "no question")])


TOY = DatasetFormat(
    key="toy", description="a toy set", read=_read, record_id=lambda i: f"record {i}", answer_type="choice",
    official_parser="choice", official_scorer="choice", source="example/toy@0123abc", licence="CC BY 4.0",
    docs_row=DocsRow("Toy", "made here", "toy.jsonl", "how-to/extend-povagent.md"), prompt_profile=PromptProfile("toy", lambda q: q.question, "made here"),
)  # fmt: skip


class ToyPlugin:
    @hookimpl
    def register_dataset_formats(self, register):
        register("toy", TOY, description=TOY.description)


class NotAFormatPlugin:
    @hookimpl
    def register_dataset_formats(self, register):
        register("odd", {"key": "odd"})


class WrongKeyPlugin:
    @hookimpl
    def register_dataset_formats(self, register):
        register("other", TOY)


@pytest.fixture
def with_plugin(povagent_host):
    added: list[str] = []

    def add(plugin: object, name: str) -> None:
        povagent_host.add_plugin(plugin, name=name, source=f"plugin {name}")
        added.append(name)

    yield add
    for name in added:
        povagent_host.remove_plugin(name)


def test_a_registered_format_is_what_the_host_hands_back(povagent_host, with_plugin):
    with_plugin(ToyPlugin(), "toy-plugin")
    assert "toy" in povagent_host.names("format")
    assert registered_format(povagent_host, "toy") is TOY
    assert registered_formats(povagent_host)["toy"] is TOY
    assert povagent_host.entry("format", "toy").source == "plugin toy-plugin"


def test_a_format_registered_twice_names_both_plugins(povagent_host, with_plugin):
    with_plugin(ToyPlugin(), "first")
    with_plugin(ToyPlugin(), "second")
    with pytest.raises(PluginError, match=r"format name 'toy' is registered twice") as err:
        povagent_host.names("format")
    assert "plugin first" in str(err.value) and "plugin second" in str(err.value)


def test_something_else_registered_as_a_format_is_refused_naming_its_plugin(povagent_host, with_plugin):
    with_plugin(NotAFormatPlugin(), "odd-plugin")
    with pytest.raises(PluginError, match=r"plugin odd-plugin: registered a dataset format that is a dict"):
        registered_format(povagent_host, "odd")


def test_a_format_registered_under_another_key_is_refused(povagent_host, with_plugin):
    with_plugin(WrongKeyPlugin(), "wrong-key")
    with pytest.raises(PluginError, match=r"registered as 'other' has key 'toy'"):
        registered_format(povagent_host, "other")


def test_a_format_with_an_empty_official_rule_is_refused(povagent_host, with_plugin):
    class NoRule:
        @hookimpl
        def register_dataset_formats(self, register):
            from dataclasses import replace

            register("toy", replace(TOY, official_scorer=""))

    with_plugin(NoRule(), "no-rule")
    with pytest.raises(PluginError, match=r"plugin no-rule: dataset format 'toy' leaves official_scorer empty"):
        registered_format(povagent_host, "toy")


def test_problems_of_lists_what_the_reader_left_out(tmp_path):
    file = tmp_path / "toy.jsonl"
    file.write_text("{}\n")
    assert [str(p) for p in TOY.problems_of(FormatRead(file))] == [str(Problem(str(file), "record 3", "no question"))]


def test_problems_of_a_file_the_reader_cannot_read_is_one_problem(tmp_path):
    missing = tmp_path / "absent.jsonl"
    assert TOY.problems_of(FormatRead(missing)) == [Problem(str(missing), "", "not found")]
