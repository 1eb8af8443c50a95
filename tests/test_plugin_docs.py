"""docs/reference/plugins.md and the code it documents cannot drift apart: the page's reference sections
and example code are generated (``python tools/plugin_docs.py``), and these tests fail while
the page is out of date, saying which command brings it back."""

from __future__ import annotations

import ast
import dataclasses
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from povagent import hookspecs

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))  # the generator is a repository tool, not part of the package
import plugin_docs  # noqa: E402
from plugin_docs import COMMAND, PluginDocsError, check_page, hookspec_names, main, markdown, render_page  # noqa: E402

PAGE = ROOT / "docs" / "reference" / "plugins.md"
EXAMPLES = sorted((ROOT / "examples" / "plugins").glob("*.py"))


def test_the_page_is_up_to_date_with_the_code():
    problem = check_page(PAGE)
    assert problem is None, problem


def test_the_page_generates_every_hook_the_base_classes_and_the_four_data_types():
    text = PAGE.read_text(encoding="utf-8")
    for block in ("hooks", "interfaces", *(f"fields {t}" for t in (
        "povagent.dataset.instances:Instance", "povagent.exchange.messages:Request",
        "povagent.exchange.messages:Response", "povagent.answers.spec:ParsedAnswer",
    ))):  # fmt: skip
        assert f"<!-- generated: {block} -->" in text, block
    for name in hookspec_names():
        assert f"### `{name}`" in text and markdown(getattr(hookspecs, name).__doc__.strip().splitlines()[0]) in text


def test_every_example_is_shown_on_the_page_exactly_as_its_file():
    text = PAGE.read_text(encoding="utf-8")
    assert len(EXAMPLES) == 4
    for path in EXAMPLES:
        assert f"```python\n{path.read_text(encoding='utf-8').rstrip()}\n```" in text, path.name


def test_everything_an_example_imports_from_povagent_is_named_on_the_page():
    """A plugin author writes these from the page alone: every povagent module an example
    imports from, and every name it imports, appears in the page's text."""
    text = PAGE.read_text(encoding="utf-8")
    outside_examples = text
    for path in EXAMPLES:  # the examples' own code does not count as the page saying it
        outside_examples = outside_examples.replace(path.read_text(encoding="utf-8").rstrip(), "")
    for path in EXAMPLES:
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("povagent"):
                assert node.module in outside_examples, f"{path.name}: module {node.module}"
                for alias in node.names:
                    assert alias.name in outside_examples, f"{path.name}: {node.module}.{alias.name}"


def test_a_changed_hookspec_docstring_makes_the_check_fail_and_name_the_command(monkeypatch):
    monkeypatch.setattr(hookspecs.register_scorers, "__doc__", "Contribute scorers (reworded).")
    problem = check_page(PAGE)
    assert problem is not None and f"run `{COMMAND}`" in problem and "plugins.md is out of date" in problem


def test_a_changed_example_makes_the_check_fail(tmp_path):
    (tmp_path / "docs" / "reference").mkdir(parents=True)
    shutil.copytree(ROOT / "examples" / "plugins", tmp_path / "examples" / "plugins")
    (tmp_path / "examples" / "plugin_package").mkdir()
    shutil.copy(ROOT / "examples" / "plugin_package" / "pyproject.toml", tmp_path / "examples" / "plugin_package")
    page = tmp_path / "docs" / "reference" / "plugins.md"
    shutil.copy(PAGE, page)
    assert check_page(page) is None
    example = tmp_path / "examples" / "plugins" / "within_radius_scorer.py"
    example.write_text(example.read_text().replace("radius: float = 0.1", "radius: float = 0.2"))
    assert check_page(page) is not None
    assert main([str(page), "--check"]) == 1
    assert main([str(page)]) == 0  # regenerates
    assert check_page(page) is None and "radius: float = 0.2" in page.read_text()


def test_the_command_runs_as_a_module_from_the_repository_root():
    done = subprocess.run([sys.executable, str(ROOT / "tools" / "plugin_docs.py"), "--check"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "up to date" in done.stdout, done.stderr


def test_a_field_without_a_note_is_refused_naming_it(monkeypatch):
    notes = dict(plugin_docs.FIELD_NOTES["Usage"])
    del notes["cost_usd"]
    notes["tokens"] = "a field that no longer exists"
    monkeypatch.setitem(plugin_docs.FIELD_NOTES, "Usage", notes)
    with pytest.raises(PluginDocsError, match=r"fields without a note: \['cost_usd'\]; notes for no field: \['tokens'\]"):
        plugin_docs.render_fields("povagent.exchange.messages:Usage")


def test_an_unknown_or_unclosed_block_is_an_error_naming_the_page_and_line(tmp_path):
    page = tmp_path / "p.md"
    with pytest.raises(PluginDocsError, match="unknown generated block 'everything'"):
        render_page("# t\n<!-- generated: everything -->\n<!-- end generated -->\n", page)
    with pytest.raises(PluginDocsError, match=r"p.md:3: '<!-- generated: hooks -->' has no '<!-- end generated -->'"):
        render_page("# t\n\n<!-- generated: hooks -->\nold\n", page)


def test_rendering_twice_changes_nothing():
    text = PAGE.read_text(encoding="utf-8")
    assert render_page(render_page(text, PAGE), PAGE) == text


def test_rest_docstrings_become_markdown():
    doc = "See :class:`~povagent.interfaces.Backend` and :func:`povagent.x.f`, ``code``::\n\n    a = 1\n\nEnd."
    assert markdown(doc) == "See `Backend` and `povagent.x.f`, `code`:\n\n```\na = 1\n```\n\nEnd."


def test_the_parser_table_of_docs_official_is_up_to_date_with_the_registrations():
    problem = check_page(ROOT / "docs" / "explanation" / "official.md")
    assert problem is None, problem


def test_every_built_in_parser_says_what_it_reads_and_how_it_compares_with_official():
    from povagent.plugins import build_plugin_host

    for entry in build_plugin_host().entries("parser"):
        if entry.source.startswith("built-in "):
            assert getattr(entry.factory, "reads", ""), entry.name
            assert getattr(entry.factory, "beside_official", ""), entry.name
            assert f"| `{entry.name}` | {entry.factory.reads.replace('|', chr(92) + '|')} |" in plugin_docs.render_parsers()


def test_a_stale_page_other_than_the_plugin_reference_names_the_command_that_rewrites_it():
    official = ROOT / "docs" / "explanation" / "official.md"
    text = official.read_text(encoding="utf-8")
    stale = render_page(text, official).replace("| `official` |", "| `official-renamed` |", 1)
    assert stale != text
    copy = official.with_name("official.stale-copy.md")
    try:
        copy.write_text(stale, encoding="utf-8")
        problem = check_page(copy)
    finally:
        copy.unlink()
    assert problem is not None and "run `python tools/plugin_docs.py docs/explanation/official.stale-copy.md`" in problem
    # and the bare command rewrites exactly the page the message names by default
    plugins_page = ROOT / "docs" / "reference" / "plugins.md"
    assert check_page(plugins_page) is None


def test_the_tools_table_of_the_active_how_to_is_generated_from_the_registrations():
    active = ROOT / "docs" / "how-to" / "active.md"
    assert "<!-- generated: tools -->" in active.read_text(encoding="utf-8")
    assert check_page(active) is None, check_page(active)


def test_a_tool_whose_explanation_changed_makes_the_active_how_to_stale(monkeypatch):
    from povagent_plugins.tools import turn

    monkeypatch.setattr(turn, "TOOL", dataclasses.replace(turn.TOOL, explained="rotate (reworded)"))
    problem = check_page(ROOT / "docs" / "how-to" / "active.md")
    assert problem is not None and "run `python tools/plugin_docs.py docs/how-to/active.md`" in problem
