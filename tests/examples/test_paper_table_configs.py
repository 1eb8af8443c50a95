"""Every shipped config that reproduces a paper table reads answers the official way, and the
docs' profile table says what ``povagent plugins --json`` says.

A config reproduces a paper table when its first line is ``# paper-table: <which table>`` (a
comment, so the loader is untouched). Every cell of such a config must use an official reading
(``official``, or ``robopoint-official`` for RoboPoint), and, where the cell's model is a
profile, the profile's own default parser: a repair parser (``json``, ``rescale-1000``, ...)
would print repaired numbers under the paper's headline.
"""

from __future__ import annotations

import functools
import json
import re
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.config.pipeline import load_pipeline
from povagent.plugins import get_plugin_host
from povagent.results.official_reading import OFFICIAL_PARSERS
from povagent.run.sweep import expand_sweep

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE_CONFIGS = sorted((ROOT / "examples").glob("**/*.yaml"))
PAPER_TABLE = re.compile(r"^# paper-table: (\S.*)$")


def paper_table(path: Path) -> str | None:
    """The table a config says it reproduces (its first line), or ``None``."""
    first = path.read_text(encoding="utf-8").split("\n", 1)[0]
    m = PAPER_TABLE.match(first)
    return m.group(1) if m else None


def cell_configs(path: Path):
    """The resolved pipeline of every cell (a sweep) or the pipeline itself."""
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    if isinstance(data, dict) and "base" in data:
        return [cell.config for cell in expand_sweep(path)[1]]
    return [load_pipeline(path)]


def repairs_in(path: Path) -> list[str]:
    """Every cell of ``path`` that is not read the official way, as ``parser (model)``."""
    profiles = get_plugin_host().profiles()
    bad = []
    for config in cell_configs(path):
        parser = config.parser.name
        model = config.model or config.backend.options.get("model")
        profile = profiles.get(model) if isinstance(model, str) else None
        default = getattr(profile, "default_parser", None)
        if parser not in OFFICIAL_PARSERS or (default in OFFICIAL_PARSERS and parser != default):
            bad.append(f"{parser} ({model})")
    return bad


PAPER_CONFIGS = [p for p in EXAMPLE_CONFIGS if paper_table(p)]


def test_the_paper_sweeps_say_which_table_they_reproduce():
    names = {p.name for p in PAPER_CONFIGS}
    assert {"paper_main_table.yaml", "paper_main_table_given_only.yaml", "paper_ablation.yaml"} <= names
    # a config named for the paper cannot drop the marker and escape the check below
    assert all(paper_table(p) for p in EXAMPLE_CONFIGS if p.name.startswith("paper_"))


@pytest.mark.parametrize("path", PAPER_CONFIGS, ids=lambda p: p.name)
def test_a_paper_table_config_reads_every_answer_officially(path):
    assert repairs_in(path) == []


def test_a_paper_table_config_with_a_repair_parser_is_caught(tmp_path):
    """The check above fails on a repair: the shipped main table with ``parser: json``."""
    text = (ROOT / "examples" / "sweeps" / "paper_main_table.yaml").read_text(encoding="utf-8")
    bent = tmp_path / "paper_main_table.yaml"
    bent.write_text(text.replace("parser: official", "parser: json"), encoding="utf-8")
    assert repairs_in(bent) and all(r.startswith("json") for r in repairs_in(bent))


# -- docs tables against `povagent plugins --json` --------------------------------------------


@functools.cache
def plugins_json() -> dict:
    """What ``povagent plugins --json`` prints."""
    out = CliRunner().invoke(app, ["plugins", "--json"])
    assert out.exit_code == 0, out.output
    return json.loads(out.stdout)


def markdown_table(text: str, header: str) -> list[list[str]]:
    """The rows of the markdown table whose header line starts with ``header`` (cells with
    their backticks removed)."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([c.strip().strip("`") for c in line.strip().strip("|").split("|")])
    return rows


def profile_table_disagreements(page: str, listed: dict) -> list[str]:
    """Where the docs' profile table and the plugin listing differ (name, model, parser)."""
    documented = {r[0]: (r[1], r[2]) for r in markdown_table(page, "| profile | litellm model | parser |")}
    registered = {p["name"]: (p["model"], p["parser"]) for p in listed["profile"]}
    out = [f"{n}: docs {documented.get(n)} != plugins {registered.get(n)}" for n in sorted(set(documented) | set(registered))
           if documented.get(n) != registered.get(n)]  # fmt: skip
    return out


def test_the_backends_profile_table_agrees_with_povagent_plugins():
    listed = plugins_json()
    page = (ROOT / "docs" / "how-to" / "models.md").read_text(encoding="utf-8")
    assert profile_table_disagreements(page, listed) == []
    # and the check sees a stale row (the table as it was: gpt-5.4 read with json)
    stale = page.replace("| `gpt-5.4` | `openai/gpt-5.4` | `official` |", "| `gpt-5.4` | `openai/gpt-5.4` | `json` |")
    assert profile_table_disagreements(stale, listed) == ["gpt-5.4: docs ('openai/gpt-5.4', 'json') != plugins ('openai/gpt-5.4', 'official')"]


@pytest.mark.parametrize(("page", "header"), [("docs/explanation/official.md", "| parser | reads |")])
def test_every_parser_a_docs_table_names_is_registered(page, header):
    parsers = {p["name"] for p in plugins_json()["parser"]}
    rows = markdown_table((ROOT / page).read_text(encoding="utf-8"), header)
    named = {n.strip().strip("`") for r in rows for n in r[0].split(",")}
    assert named and named <= parsers, named - parsers
