"""Every link and path the README, the docs and the ``--help`` texts give leads somewhere in a
fresh clone: to a file git tracks (not a build output such as the generated reference pages),
and every README section a help text cites exists."""

from __future__ import annotations

import fnmatch
import posixpath
import re
import subprocess
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: A Markdown link or image: ``[text](target)``.
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
#: A path into the repository named in prose: it starts with a top-level folder of the tree.
PATH = re.compile(r"(?<![\w./-])((?:docs|povagent|plugins|examples|benchmarks|tests|tools|prompts|typecheck)/[\w./<>-]*[\w>])")
#: A README section cited by name: ``... under 'Pipelines' in the README``.
README_SECTION = re.compile(r"'([^']+)' in the README")


@lru_cache(maxsize=1)
def tracked() -> frozenset[str]:
    """The files a fresh clone holds (git's index), relative to the repository's root."""
    done = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, text=True, timeout=60)
    if done.returncode != 0:
        pytest.fail(f"the link check reads the tree with git ls-files: {done.stderr.strip()}")
    return frozenset(done.stdout.split("\0")) - {""}


def exists(path: str) -> bool:
    """A tracked file or a folder holding one; an upper-case word or ``<name>`` is a placeholder
    (``povagent/schemas/output_NAME.schema.json``) that some tracked file must fill."""
    path = path.rstrip("/")
    files = tracked()
    if path in files or any(f.startswith(path + "/") for f in files):
        return True
    pattern = re.sub(r"<[^>]+>|(?<![A-Za-z])[A-Z][A-Z0-9]*(?![a-z])", "*", path)
    return pattern != path and any(fnmatch.fnmatchcase(f, pattern) or fnmatch.fnmatchcase(f, pattern + "/*") for f in files)


def ignored(path: str) -> bool:
    """Whether git ignores ``path``: a build output (``docs/_build``), named where a command writes."""
    asked = [path, path.rstrip("/") + "/"]  # a folder's pattern (_build/) matches the name with its slash
    return any(subprocess.run(["git", "check-ignore", "-q", "--no-index", p], cwd=ROOT, timeout=60).returncode == 0 for p in asked)


def named_in_prose_missing(text: str) -> list[str]:
    """The repository paths ``text`` names that a fresh clone lacks (a build output named as
    where a command writes is not one; a link to one is, see the link test)."""
    return sorted({p for p in PATH.findall(text) if not exists(p) and not ignored(p)})


def pages() -> list[str]:
    """The README and every tracked Markdown page of the docs."""
    return ["README.md", *sorted(f for f in tracked() if f.startswith("docs/") and f.endswith(".md"))]


def link_targets(page: str) -> list[tuple[str, str]]:
    """``(as written, resolved in the tree)`` for every relative link of a page."""
    text = (ROOT / page).read_text(encoding="utf-8")
    out = []
    for target in LINK.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a URL or an anchor of the same page
        resolved = posixpath.normpath(posixpath.join(posixpath.dirname(page), target.split("#", 1)[0]))
        out.append((target, resolved))
    return out


@pytest.mark.parametrize("page", pages())
def test_every_relative_link_of_a_page_leads_to_a_tracked_file(page):
    dead = [written for written, resolved in link_targets(page) if not exists(resolved)]
    assert dead == [], f"{page}: links to what a fresh clone lacks: {dead}"


@pytest.mark.parametrize("page", pages())
def test_every_repository_path_a_page_names_exists(page):
    missing = named_in_prose_missing((ROOT / page).read_text(encoding="utf-8"))
    assert missing == [], f"{page}: names paths a fresh clone lacks: {missing}"


def help_texts() -> dict[str, str]:
    """Every ``povagent`` command's help (its text and each option's), and the test servers'."""
    import typer.main

    from povagent.cli import app
    from povagent.testing import hub_server, loopback_server

    texts: dict[str, str] = {}

    def walk(command, name: str) -> None:
        texts[name] = "\n".join([command.help or "", *(getattr(p, "help", None) or "" for p in command.params)])
        for sub_name, sub in sorted(getattr(command, "commands", {}).items()):
            walk(sub, f"{name} {sub_name}")

    walk(typer.main.get_command(app), "povagent")
    for module in (loopback_server, hub_server):
        texts[f"python -m {module.__name__}"] = module.argument_parser().format_help()
    return texts


def test_the_help_texts_of_every_command_are_collected():
    texts = help_texts()
    assert {"povagent run", "povagent show-prompt", "python -m povagent.testing.loopback_server"} <= set(texts)


def test_every_path_a_help_text_names_exists():
    missing = {name: found for name, text in help_texts().items() if (found := named_in_prose_missing(text))}
    assert missing == {}


def test_every_readme_section_a_help_text_cites_exists():
    headings = set(re.findall(r"^#+\s+(.+?)\s*$", (ROOT / "README.md").read_text(encoding="utf-8"), re.M))
    cited = {name: sorted(set(README_SECTION.findall(text)) - headings) for name, text in help_texts().items()}
    assert {name: sections for name, sections in cited.items() if sections} == {}


def test_a_generated_reference_page_is_not_in_a_fresh_clone():
    """The rule the checks above hold: build outputs do not count as the tree."""
    assert not exists("docs/reference/configuration.md") and exists("docs/reference/index.md")
