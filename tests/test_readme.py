"""The README is a landing page: short, its Quickstart holds exactly two commands, and CI runs
the test one verbatim. The "What is where" table lives on the architecture page."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def quickstart_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    section = text.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```(?:bash|sh)\n(.*?)```", section, flags=re.S)
    return [line.strip() for block in blocks for line in block.strip().splitlines() if line.strip()]


def test_quickstart_has_exactly_two_commands():
    assert len(quickstart_commands()) == 2


def test_ci_runs_the_readme_test_command_verbatim():
    test_command = quickstart_commands()[1]
    assert "pytest" in test_command
    assert test_command in (ROOT / ".ci" / "run").read_text()


def test_the_main_command_installs_and_runs_the_quickstart():
    main = quickstart_commands()[0]
    assert "pip install" in main and "povagent quickstart" in main


#: The README is read in minutes: the issue that set it asked for at most this many characters.
README_MAX_CHARS = 8000

#: The page holding the "What is where" table of the source tree.
ARCHITECTURE = ROOT / "docs" / "explanation" / "architecture.md"


def test_the_readme_is_at_most_eight_thousand_characters():
    assert len((ROOT / "README.md").read_text(encoding="utf-8")) <= README_MAX_CHARS


def what_is_where() -> list[str]:
    text = ARCHITECTURE.read_text()
    section = text.split("## What is where", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"^\| `([^`]+)/` \|", section, flags=re.M)


def test_what_is_where_names_every_package_of_the_core():
    packages = sorted(f"povagent/{p.name}" for p in (ROOT / "povagent").iterdir() if (p / "__init__.py").is_file())
    listed = set(what_is_where())
    assert [p for p in packages if p not in listed] == []


def test_what_is_where_names_only_folders_that_exist():
    assert [f for f in what_is_where() if not (ROOT / f).is_dir()] == []


def section(title: str) -> str:
    """The README's ``## title`` section."""
    return (ROOT / "README.md").read_text(encoding="utf-8").split(f"## {title}", 1)[1].split("\n## ", 1)[0]


def test_the_quickstart_house_count_is_what_the_quickstart_generates():
    import inspect

    from povagent.report.quickstart import run_quickstart

    houses = int(re.search(r"Generate a (\d+)-house", section("Quickstart")).group(1))
    assert houses == inspect.signature(run_quickstart).parameters["houses"].default


def test_the_suite_times_are_the_measured_ones():
    wall, cpu = re.search(r"about ([\d.]+) min after the install \((\d+) s of CPU\)", " ".join(section("Quickstart").split())).groups()
    results = (ROOT / "benchmarks" / "RESULTS.md").read_text(encoding="utf-8")
    assert f"| the README's test command, wall time | {wall} min |" in results
    assert f"| the README's test command, CPU time | {cpu} s |" in results


def job_commands() -> list[list[str]]:
    block = re.search(r"```bash\n(.*?)```", section("Four jobs, one command each"), flags=re.S).group(1)
    return [line.split("#", 1)[0].split() for line in block.strip().splitlines()]


def test_the_four_jobs_are_four_povagent_commands_that_exist():
    from typer.main import get_command

    from povagent.cli import app

    commands = get_command(app).commands  # type: ignore[attr-defined]
    jobs = job_commands()
    assert len(jobs) == 4 and all(job[0] == "povagent" and job[1] in commands for job in jobs)
    assert [arg for job in jobs for arg in job[2:] if arg.startswith("examples/") and not (ROOT / arg).is_file()] == []


def test_each_job_links_its_how_to():
    linked = set(re.findall(r"\]\((docs/how-to/[\w-]+\.md)\)", section("Four jobs, one command each")))
    assert {"docs/how-to/paper-tables.md", "docs/how-to/perspective-sets.md", "docs/how-to/active.md", "docs/how-to/human-study.md"} <= linked
