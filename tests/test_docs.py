"""The documentation cannot drift from the code, link nowhere, or carry a figure without a source.

* The generated reference (``docs/_ext/reference_pages.py``) names every CLI command of the typer
  app, every key of the pipeline and sweep YAML, every registered model profile; the plugin
  reference names every hook.
* Every relative link of the README and of ``docs/`` reaches a file, and every ``#anchor`` a
  heading of that file (the check Sphinx's ``linkcheck`` cannot do offline).
* Every measured figure in the README's or the docs' prose (a number with a unit such as ``x``,
  ``ms``, ``s``, ``%``, ``MB``) appears in ``benchmarks/RESULTS.md``, which is current with the
  benchmarks' JSON; numbers that are settings or facts, not measurements, are listed below.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"


def load_module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def reference():
    """The generated reference pages, rendered from the code as the docs build renders them."""
    pages = load_module(DOCS / "_ext" / "reference_pages.py", "povagent_docs_reference_pages")
    return {stem: render() for stem, render in pages.RENDER.items()}


# -- the reference covers the code --------------------------------------------------------------
def test_every_cli_command_has_a_section_in_the_cli_reference(reference):
    import typer.main

    from povagent.cli import app

    commands = sorted(typer.main.get_command(app).commands)  # type: ignore[attr-defined]
    assert commands, "the typer app lists no command"
    assert [c for c in commands if f"## `povagent {c}`" not in reference["cli"]] == []


def yaml_keys(model, prefix: str) -> list[str]:
    """Every key of ``model`` and of the models nested in it, as dotted paths."""
    import typing

    from pydantic import BaseModel

    keys = []
    for name, field in model.model_fields.items():
        keys.append(f"{prefix}.{name}")
        stack = [field.annotation]
        while stack:
            a = stack.pop()
            if isinstance(a, type) and issubclass(a, BaseModel):
                keys += yaml_keys(a, f"{prefix}.{name}")
            stack.extend(typing.get_args(a))
    return keys


def test_every_pipeline_and_sweep_key_is_in_the_yaml_reference(reference):
    from povagent.config.models import PipelineConfig
    from povagent.config.sweep_models import SweepConfig

    page = reference["configuration"]
    missing = []
    for key in yaml_keys(PipelineConfig, "pipeline") + yaml_keys(SweepConfig, "sweep"):
        section, leaf = key.rsplit(".", 1)
        heading = f"## `{section}` ("
        body = page.split(heading, 1)[1].split("\n## ", 1)[0] if heading in page else ""
        if f"| `{leaf}` |" not in body:
            missing.append(key)
    assert missing == []


def test_every_model_profile_is_in_the_profiles_reference(reference):
    from povagent.plugins import get_plugin_host

    names = get_plugin_host(()).names("profile")
    assert names
    assert [n for n in names if f"| `{n}` |" not in reference["profiles"]] == []


def test_every_dataset_format_has_its_row_in_the_datasets_reference(reference):
    from povagent.dataset.formats import registered_formats
    from povagent.plugins import get_plugin_host

    formats = registered_formats(get_plugin_host(()))
    assert {"povbench", "generated", "realworld", "viewspatial", "mindcube", "3dsrbench"} <= set(formats)
    rows = [line for line in reference["datasets"].splitlines() if line.startswith("| ")][1:]  # the header row first
    assert [line.split(" | ")[1] for line in rows] == [f"`{k}`" for k in formats]
    for (key, fmt), line in zip(formats.items(), rows):
        cells = [c.strip() for c in line.strip("|").split(" | ")]
        assert cells[0] == fmt.docs_row.name and cells[4:7] == [f"`{fmt.answer_type}`", f"`{fmt.official_parser}`", f"`{fmt.official_scorer}`"], key
        assert cells[7:9] == [fmt.source, fmt.licence] and (DOCS / fmt.docs_row.how_to).is_file(), key


def test_the_perspective_sets_table_is_the_registered_formats_rows():
    """The how-to's table of sets is every format that names the page as its how-to, each row as
    its format says (a format added without its row, or a row left for a removed format, fails)."""
    from povagent.dataset.formats import registered_formats
    from povagent.plugins import get_plugin_host

    page = "how-to/perspective-sets.md"
    text = (DOCS / page).read_text(encoding="utf-8")
    table = text.split("| set | Hub dataset | licence | file | `format` |\n|---|---|---|---|---|\n", 1)[1].split("\n\n", 1)[0]
    expected = [
        f"| {f.docs_row.name} | {f.docs_row.where} | {f.licence} | {f.docs_row.path} | `{f.key}` |"
        for f in registered_formats(get_plugin_host(())).values()
        if f.docs_row.how_to == page
    ]
    assert sorted(table.splitlines()) == sorted(expected)


def test_every_file_format_carries_its_json_schema(reference):
    page = reference["formats"]
    for title in ("results.jsonl", "predictions export", "release: pair_file", "release: exploration_log"):
        section = page.split(f"## {title}", 1)[1].split("\n## ", 1)[0]
        assert '"properties"' in section or '"items"' in section or '"additionalProperties"' in section, title


def test_every_hook_is_in_the_plugin_reference():
    hookspec_names = load_module(ROOT / "tools" / "plugin_docs.py", "plugin_docs").hookspec_names

    page = (DOCS / "reference" / "plugins.md").read_text(encoding="utf-8")
    assert [h for h in hookspec_names() if f"`{h}" not in page] == []


def test_the_how_to_toctree_takes_every_page_of_its_folder():
    """Pages other work adds to docs/how-to/ join the site without an edit (a glob)."""
    index = (DOCS / "how-to" / "index.md").read_text(encoding="utf-8")
    assert ":glob:" in index and re.search(r"^\*$", index, flags=re.M)


# -- links ---------------------------------------------------------------------------------------
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)|!\[[^\]]*\]\(([^)\s]+)\)")


def prose(text: str) -> str:
    """``text`` without fenced code blocks, inline code and HTML comments."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"<!--.*?-->", "", text, flags=re.S)
    return re.sub(r"`[^`\n]*`", "", text)


def slug(heading: str) -> str:
    """A heading's anchor as GitHub and MyST (``myst_heading_anchors``) make it."""
    text = re.sub(r"[`*_]|\[([^\]]*)\]\([^)]*\)", lambda m: m.group(1) or "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(text: str) -> set[str]:
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    return {slug(h) for h in re.findall(r"^#{1,6} (.+)$", text, flags=re.M)}


def pages_with_links() -> list[Path]:
    pages = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]
    return [p for p in pages if "_build" not in p.parts]


def broken_links(page: Path, generated: dict[Path, str] | None = None) -> list[str]:
    """``page``'s relative links that reach no file, or no heading of a Markdown file;
    ``generated`` holds pages the docs build writes (path -> text)."""
    generated = generated or {}
    broken = []
    for a, b in LINK.findall(prose(page.read_text(encoding="utf-8"))):
        target = a or b
        if re.match(r"^[a-z]+:", target):  # http(s), mailto: outside the offline check
            continue
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if dest in generated:
            text = generated[dest]
        elif dest.exists():
            text = dest.read_text(encoding="utf-8") if dest.suffix == ".md" else ""
        else:
            broken.append(f"{page.name}: {target} (no such file)")
            continue
        if anchor and dest.suffix == ".md" and anchor not in anchors(text):
            broken.append(f"{page.name}: {target} (no such heading)")
    return broken


def test_every_relative_link_of_the_readme_and_the_docs_resolves(reference):
    generated = {(DOCS / "reference" / f"{stem}.md").resolve(): text for stem, text in reference.items()}
    broken = [f"{page.relative_to(ROOT)}: {b}" for page in pages_with_links() for b in broken_links(page, generated)]
    assert broken == []


def test_a_link_to_a_missing_file_or_heading_is_reported(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("# Title\n\n## A section\n\n[a](#a-section) [b](#no-such-section) [c](missing.md) [d](page.md#title)\n")
    assert broken_links(page) == ["page.md: #no-such-section (no such heading)", "page.md: missing.md (no such file)"]


# -- figures -------------------------------------------------------------------------------------
#: A number and its unit; a ratio's ``x`` is written against the number (``0.35x``: ``8 x 6`` is a grid).
FIGURE = re.compile(r"(?<![\w.\-/])(\d[\d,]*(?:\.\d+)?)(x|\s?(?:ms|s|%|MB|GB|KB|MiB|GiB|KiB))(?!\w)")

#: Numbers with units that are settings, bounds or facts of the benchmark, not measurements.
NOT_MEASUREMENTS = {
    "95%",  # the confidence level of every interval
    "512x",  # the benchmark's frame size (512x512)
    "1 MiB", "64 MiB", "4096 MiB", "64 KiB",  # config and download bounds; the test tmpfs
    "256 MiB", "512 MiB",  # bounds of an image file and of a results line read back
    "5 s", "10 s", "20 s", "90 s", "120 s", "0.25 s", "0.2 s",  # timeouts, polling, lease and TF tolerance settings
    "16 GB",  # an 8B model's weights in bfloat16 (arithmetic, not a measurement)
    "516 MiB", "226 KiB",  # the size of the public release (a fact of the data set)
    "429 s",  # "429s": HTTP 429 answers, plural
}

#: Generated reference pages quote the code's own strings; they are not prose we write.
GENERATED = {"cli.md", "configuration.md", "formats.md", "profiles.md"}


def figures(text: str) -> list[str]:
    """The figures of ``text``'s prose, written as RESULTS.md writes them (``0.35x``, ``1.3 s``)."""
    found = [(n, u.strip()) for n, u in FIGURE.findall(prose(text))]
    return [f"{n}{u}" if u in ("x", "%") else f"{n} {u}" for n, u in found]


def unsourced_figures(text: str, results: str) -> list[str]:
    return [f for f in figures(text) if f not in NOT_MEASUREMENTS and f not in results]


def test_every_figure_in_the_readme_and_the_docs_has_a_source_in_results():
    results = (ROOT / "benchmarks" / "RESULTS.md").read_text(encoding="utf-8")
    pages = [p for p in pages_with_links() if not (p.parent.name == "reference" and p.name in GENERATED)]
    unsourced = [f"{p.relative_to(ROOT)}: {f}" for p in pages for f in unsourced_figures(p.read_text(encoding="utf-8"), results)]
    assert unsourced == []


def test_a_figure_without_a_source_is_found():
    assert unsourced_figures("scoring is 0.36x of the old CPU, at 95% confidence", "| 0.35x |") == ["0.36x"]


def test_results_md_is_current_with_the_benchmarks_json():
    writer = load_module(ROOT / "benchmarks" / "write_results.py", "povagent_write_results")
    assert writer.main(["--check"]) == 0, "run python benchmarks/write_results.py"
