"""The active mode's how-to counts the built-in tools and the point task's in words; the
counts come from the registrations, so a tool added or dropped fails here until the page says so."""

from __future__ import annotations

from pathlib import Path

from povagent.plugins import build_plugin_host

PAGE = Path(__file__).resolve().parents[2] / "docs" / "how-to" / "active.md"
WORDS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven", "twelve")


def built_in(task: str | None) -> list[str]:
    """The built-in tools (``povagent_plugins.tools``) an episode of ``task`` offers (``None``: all)."""
    tools = build_plugin_host().tools(task)
    return [name for name in tools.names if tools.sources[name].startswith("built-in povagent_plugins.tools.")]


def test_the_page_counts_every_built_in_tool():
    assert f"the {WORDS[len(built_in(None))]} below by `povagent_plugins.tools`" in PAGE.read_text(encoding="utf-8")


def test_the_page_counts_the_point_tasks_tools():
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    word = WORDS[len(built_in("point"))]
    assert f"the point task offers the first {word}" in text and f"offers exactly its {word} tools" in text
