"""Tables and lists in an 80-column terminal: no line wider than the terminal, and nothing a
reader looks up (a slice, a sweep cell, a plugin, a number) cut short or broken mid-word."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app
from povagent.cli.console_width import fitted_table, path_in_line

runner = CliRunner()
NARROW = {"COLUMNS": "80"}
SLICES = ("overall", "Inferred (A)", "Stated (B)", "Given (C)", "right", "left", "front", "up")


def widest(text: str) -> int:
    return max(len(line) for line in text.splitlines())


def row_of(text: str, label: str) -> list[str]:
    """The cells of the table row whose first cell is ``label`` (whole, on one line)."""
    for line in text.splitlines():
        cells = [c.strip() for c in line.split("│")[1:-1]]
        if cells and cells[0] == label:
            return cells
    raise AssertionError(f"no row labelled {label!r} in\n{text}")


@pytest.fixture
def center_run(tmp_path, mini_root):
    """A finished center-baseline run over the hand-made dataset, and what ``run`` printed."""
    pipeline = tmp_path / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center", "output": str(tmp_path / "run")}))
    result = runner.invoke(app, ["run", str(pipeline), "--quiet"], env=NARROW)
    assert result.exit_code == 0, result.output
    return tmp_path / "run", result.stdout


def test_the_run_summary_fits_and_keeps_labels_and_numbers_whole(center_run):
    _, shown = center_run
    assert widest(shown) <= 80, shown
    for label in SLICES:
        cells = row_of(shown, label)
        assert cells[-1].count("/") == 1 and cells[-1].replace(" ", "").replace("/", "").isdigit()
    assert [line for line in shown.splitlines() if line.startswith("│") and "…" in line] == []
    # the run folder in the title is shortened in its middle: its last folder is still there
    title = shown.splitlines()[0].strip()
    assert title.endswith("/run (center / basic / official)") and len(title) <= 80


def test_a_real_world_run_prints_its_success_table_in_80_columns(tmp_path, monkeypatch):
    """The success table of a set without official ground truth, its long run folder
    shortened in the title's first line (examples/realworld_demo, run from the repository)."""
    monkeypatch.chdir(Path(__file__).resolve().parents[2])
    out = tmp_path / "a-rather-long-folder-name" / "for-the-real-world-demo" / "run"
    result = runner.invoke(app, ["run", "examples/realworld_demo/pipeline.yaml", "-o", str(out), "-q"], env=NARROW)
    assert result.exit_code == 0, result.output
    shown = result.stdout
    assert widest(shown) <= 80, shown
    first, second = (line.strip() for line in shown.splitlines()[:2])
    assert first.endswith("for-the-real-world-demo/run (center / basic / official)") and "…" in first
    assert second == "success rate (unanswered = failure)"
    assert row_of(shown, "overall")[1:] == ["0.0%", "0 / 6", "100.0%", "6 / 6"]


def test_score_tables_fit_80_columns(center_run, mini_root):
    run_dir, _ = center_run
    result = runner.invoke(app, ["score", "--predictions", str(run_dir), "--dataset", str(mini_root)], env=NARROW)
    assert result.exit_code == 0, result.output
    assert widest(result.stdout) <= 80, result.stdout
    assert row_of(result.stdout, "overall")[1:] == ["0.208", "0.102", "100.0%", "100.0%", "0.208", "18 / 18"]


def test_the_sweep_dry_run_names_every_cell_in_full(tmp_path, mini_root):
    (tmp_path / "base.yaml").write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center"}))
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "base.yaml",
        "output": str(tmp_path / "a-rather-long-folder-name-for-the-sweep" / "ablation-of-every-strategy"),
        "axes": {"strategy": ["basic", "o-plot", "oa-plot", "cot", "spatial-cot"], "backend": ["center", "random"]},
    }))  # fmt: skip
    result = runner.invoke(app, ["sweep", str(tmp_path / "sweep.yaml"), "--dry-run"], env=NARROW)
    assert result.exit_code == 0, result.output
    assert widest(result.stdout) <= 80, result.stdout
    for backend in ("center", "random"):
        for strategy in ("basic", "o-plot", "oa-plot", "cot", "spatial-cot"):
            cells = row_of(result.stdout, f"{backend}__{strategy}")
            assert all(c.replace(",", "").isdigit() for c in cells[1:]), cells
    # the output folder is shortened in its middle: its last folder still names the sweep
    assert "…" in result.stdout and "ablation-of-every-strategy" in result.stdout


def test_the_sweep_table_fits_and_names_every_cell_in_full(tmp_path, mini_root):
    (tmp_path / "base.yaml").write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center"}))
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "base.yaml",
        "output": str(tmp_path / "a-rather-long-folder-name-for-the-sweep" / "strategies"),
        "axes": {"strategy": ["basic", "spatial-cot"], "backend": ["center", "random"]},
    }))  # fmt: skip
    result = runner.invoke(app, ["sweep", str(tmp_path / "sweep.yaml"), "--quiet"], env=NARROW)
    assert result.exit_code == 0, result.output
    table = result.stdout.split("sweep sweep.yaml (4 cells) -> ", 1)[1]
    assert widest(table) <= 80, table
    assert row_of(table, "center__spatial-cot")[1:] == ["0.208", "100.0%", "18 / 18"]  # read officially: no column beside
    assert row_of(table, "random__basic")[3] == "18 / 18"


def test_plugins_fit_80_columns_with_every_name_and_description():
    listing = json.loads(runner.invoke(app, ["plugins", "--json"]).stdout)
    result = runner.invoke(app, ["plugins"], env=NARROW)
    assert result.exit_code == 0, result.output
    shown = result.stdout
    assert widest(shown) <= 80, shown
    rows = [line.split("│")[1:-1] for line in shown.splitlines() if line.startswith("│")]
    first_cells = {r[0].strip() for r in rows}
    assert {"backends", "strategies", "parsers", "scorers", "judges", "model profiles"} <= first_cells
    # descriptions wrap (long words fold): compared with the line breaks taken out
    descriptions = "".join("".join(r[1].split()) for r in rows if len(r) > 1)
    for kind, entries in listing.items():
        for entry in entries if kind != "failures" else ():
            assert entry["name"] in first_cells
            assert "".join(entry["description"].split()) in descriptions, entry


def test_validate_on_a_terminal_wraps_each_problem_under_its_file(on_a_terminal):
    """On a terminal (a pseudo-terminal here) problems wrap to its width, continuation lines
    indented; piped, each stays on one line (tests/cli/test_dataset_commands.py)."""
    lines, code, _ = on_a_terminal
    assert code == 1
    assert max(len(line) for line in lines) <= 80, lines
    starts = [line for line in lines if line.startswith("artifacts/train_house_00002/")]
    assert len(starts) == 9
    assert all(line.startswith(("artifacts/", "    ")) for line in lines), lines


def test_a_table_narrower_than_its_content_wraps_headers_never_numbers():
    from rich.console import Console

    console = Console(width=80, record=True)
    rows = [["a sweep cell with a long name", "1,234,567", "12 / 1,800", "100.0%"]] * 3
    headers = ("requests still to make", "answered / total", "response rate")
    console.print(fitted_table([("cell", "label")] + [(h, "number") for h in headers], rows))
    text = console.export_text()
    assert widest(text) <= 80
    assert text.count("1,234,567") == 3 and text.count("12 / 1,800") == 3


def test_a_path_in_a_title_keeps_its_start_and_end():
    title = path_in_line("/home/someone/experiments/povbench/runs/2026-11-22/gpt-5.4-spatial-cot", " (litellm / cot / json)", width=60)
    assert len(title) == 60
    assert title.startswith("/home/") and title.endswith("gpt-5.4-spatial-cot (litellm / cot / json)")


def label_lines(text: str) -> list[tuple[str, list[str]]]:
    """Each table row's first cell as printed, its lines in order, with the row's other cells
    (from its first line): a label broken over lines is gathered back."""
    out: list[tuple[str, list[str]]] = []
    for line in text.splitlines():
        if not line.startswith("│"):
            continue
        cells = [c.strip() for c in line.split("│")[1:-1]]
        if any(cells[1:]) or not out:
            out.append((cells[0], cells[1:]))
        else:  # a continuation line of the label above
            out[-1] = (out[-1][0] + "\n" + cells[0], out[-1][1])
    return out


def test_long_cell_names_in_the_dry_run_break_between_words_never_inside_one(tmp_path, mini_root):
    """Cell names of real sweeps (a dated model, a strategy, a parser) are longer than the
    room beside five number columns: each goes on over lines, broken after ``__`` or ``-``,
    and the lines joined give the name back."""
    (tmp_path / "base.yaml").write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "center"}))
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump({
        "base": "base.yaml",
        "output": str(tmp_path / "out"),
        "overrides": {"openai-gpt-4o-mini-2024-07-18-with-spatial-cot": {}, "qwen2.5-vl-72b-instruct-awq-official-parse": {}},
        "axes": {"strategy": ["spatial-cot", "oa-plot"], "conditions": ["a", "c"]},
    }))  # fmt: skip
    result = runner.invoke(app, ["sweep", str(tmp_path / "sweep.yaml"), "--dry-run"], env=NARROW)
    assert result.exit_code == 0, result.output
    assert widest(result.stdout) <= 80, result.stdout
    names = [f"{s}__{c}__{o}" for s in ("spatial-cot", "oa-plot") for c in ("a", "c")
             for o in ("openai-gpt-4o-mini-2024-07-18-with-spatial-cot", "qwen2.5-vl-72b-instruct-awq-official-parse")]  # fmt: skip
    shown = {label.replace("\n", ""): (label, rest) for label, rest in label_lines(result.stdout)}
    for name in names:
        label, rest = shown[name]
        assert all(c.replace(",", "").isdigit() for c in rest), (name, rest)
        # every line ends at a separator (or the name's end): no word is cut
        for line in label.split("\n")[:-1]:
            assert line[-1] in "_-./", (name, label)
    assert "…" not in result.stdout.split("\n", 1)[1]


def third_party_site(site: Path) -> None:
    """An installed distribution (a dist-info with an entry point) under ``site`` whose entry
    point and name are long."""
    package = site / "povagent_contributed_strategies_for_observer_grounding"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "perspective_taking.py").write_text(
        "from povagent import hookimpl\n"
        "from povagent_plugins.strategies.basic import BasicStrategy\n\n"
        "@hookimpl\n"
        "def register_strategies(register):\n"
        "    register('perspective-taking', BasicStrategy, description='the basic prompt, by a third party')\n"
    )
    dist = site / "povagent_contributed_strategies_for_observer_grounding-2.11.4.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: povagent-contributed-strategies-for-observer-grounding\nVersion: 2.11.4\n")
    (dist / "entry_points.txt").write_text(
        "[povagent]\nperspective-taking = povagent_contributed_strategies_for_observer_grounding.perspective_taking\n"
    )


# The console entry run three times in one process: ``validate`` writing to the process's own
# stdout (the terminal), then ``plugins`` and ``plugins --json``, each caught in memory and
# written, with the exit codes, to the file named by the first argument.
ON_A_TERMINAL = """
import contextlib, io, json, sys
from povagent.cli import main
from povagent.cli.process_exit import exit_code_of
report, dataset = sys.argv[1:3]
sys.argv = ["povagent", "validate", dataset]
try:
    main()
    validate = 0
except SystemExit as done:
    validate = exit_code_of(done.code)
sys.stdout.flush()
shown = []
for args in (["plugins"], ["plugins", "--json"]):
    sys.argv = ["povagent", *args]
    out, err, code = io.StringIO(), io.StringIO(), 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            main()
        except SystemExit as done:
            code = exit_code_of(done.code)
    shown.append({"returncode": code, "stdout": out.getvalue(), "stderr": err.getvalue()})
with open(report, "w") as f:
    json.dump({"validate": validate, "plugins": shown}, f)
"""


@pytest.fixture(scope="module")
def on_a_terminal(tmp_path_factory, mini_root) -> tuple[list[str], int, list[dict]]:
    """(the lines ``validate`` of the hand-made dataset wrote to a pseudo-terminal, its exit code,
    what ``plugins`` then ``plugins --json`` returned and printed): one fresh process with
    COLUMNS=80 and a third-party distribution on its start-up path, where it is found (a fresh
    interpreter costs about a second of CPU)."""
    import pty

    folder = tmp_path_factory.mktemp("terminal")
    third_party_site(folder / "site")
    env = {**os.environ, **NARROW, "PYTHONPATH": os.pathsep.join([str(folder / "site"), os.environ.get("PYTHONPATH", "")])}
    leader, follower = pty.openpty()
    with open(folder / "stderr.txt", "w") as stderr:
        proc = subprocess.Popen(
            [sys.executable, "-c", ON_A_TERMINAL, str(folder / "shown.json"), str(mini_root)],
            stdout=follower, stderr=stderr, env=env, close_fds=True,
        )  # fmt: skip
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 65536)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert proc.wait(timeout=120) == 0, (folder / "stderr.txt").read_text()[-3000:]
    os.close(leader)
    shown = json.loads((folder / "shown.json").read_text())
    return b"".join(chunks).decode().replace("\r\n", "\n").splitlines(), shown["validate"], shown["plugins"]


def test_a_third_party_plugins_source_is_shown_whole_in_80_columns(on_a_terminal):
    """An installed distribution (a dist-info with an entry point, on PYTHONPATH) whose
    entry point and name are long: ``povagent plugins`` shows where it came from in full."""
    _, _, both = on_a_terminal
    done, as_json = (SimpleNamespace(**shown) for shown in both)
    assert done.returncode == 0, done.stderr
    assert widest(done.stdout) <= 80, done.stdout
    listing = json.loads(as_json.stdout)
    (entry,) = [e for e in listing["strategy"] if e["name"] == "perspective-taking"]
    assert "povagent-contributed-strategies-for-observer-grounding 2.11.4" in entry["source"]
    rows = [line.split("│")[1:-1] for line in done.stdout.splitlines() if line.startswith("│")]
    start = next(i for i, r in enumerate(rows) if r[0].strip() == "perspective-taking")
    block = []
    for r in rows[start:]:
        if r[0].strip() not in ("", "perspective-taking"):
            break
        block.append(r[1].strip())
    assert "…" not in "".join(block)
    # the source goes on over lines, each ending at a space (dropped) or after a separator:
    # joined back that way they give the source, so no word was cut
    lines = [b for b in block if b][1:]  # the description first
    assert lines[0].startswith("from ")
    source, at = "from " + entry["source"], 0
    for line in lines:
        assert source.startswith(line, at), (line, source[at:])
        at += len(line)
        if at < len(source) and source[at] == " ":
            at += 1  # broken at a space
        else:  # else only after a separator
            assert at == len(source) or line[-1] in "_-./=:", line
    assert at == len(source)
