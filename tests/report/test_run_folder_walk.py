"""A report walks a run folder through one room: every file of the folder (its config, rows,
summary, transcripts) is read by the one reader of a finished run
(:class:`povagent.results.finished_run.FinishedRun`), and the walk enters that room once; so do
``rescore``, ``export`` and ``compare``, which share the reader.

The walk is traced as it happens: ``sys.setprofile`` keeps the room of every function on the
stack (a room is the first package under ``povagent/``, or ``plugins``), and an audit hook
names each file opened for reading; a read of one of the run folder's own files is charged to
the innermost room on the stack above the ground floor (``files/``, which only opens what it is
told to). Before the reader had one owner the report's walk went results, report, results,
report, results, report, results: seven entries into two rooms.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

import povagent
from povagent.cli import app
from povagent.report.build import write_report
from povagent.report.compare import compare_runs
from povagent.report.export import export_long_csv, export_run
from povagent.results.finished_run import FinishedRun
from povagent.run.rescore import rescore_run

PACKAGE = Path(povagent.__file__).resolve().parent
PLUGINS = PACKAGE.parent / "plugins"
#: What every room stands on: opening a file for a room is not reading it for itself.
GROUND = {"files", "errors"}
#: A run folder's own files (what a command writes beside them, a rescore's folder, is not the walk).
RUN_FILES = {"config.yaml", "results.jsonl", "summary.json", "log.jsonl"}


def room_of(filename: str) -> str:
    """``report`` for ``povagent/report/collect.py``, ``plugins`` for a built-in plugin, ``""``
    for code outside povagent (the standard library, pydantic)."""
    path = Path(filename)
    if path.is_relative_to(PLUGINS):
        return "plugins"
    if not path.is_relative_to(PACKAGE):
        return ""
    parts = path.relative_to(PACKAGE).parts
    return parts[0] if len(parts) > 1 else parts[0].removesuffix(".py")


class Walk:
    """The rooms that read files of ``folder``, in order, a room named again only when another
    read the folder between (what "entering a room" is for this walk)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder.resolve()
        self.rooms: list[str] = []
        self.stack: list[str] = []
        self.reads = 0
        self.tracing = False
        self._room_of_code: dict[object, str] = {}

    def profile(self, frame, event, _arg) -> None:
        if event == "call":
            code = frame.f_code
            room = self._room_of_code.get(code)
            if room is None:
                room = self._room_of_code[code] = room_of(code.co_filename)
            self.stack.append(room)
        elif event == "return" and self.stack:
            self.stack.pop()

    def audit(self, event: str, args: tuple) -> None:
        if not self.tracing or event != "open" or not isinstance(args[0], (str, bytes, os.PathLike)):
            return
        path, mode, flags = args
        reading = not set(mode) & set("wax+") if isinstance(mode, str) else flags & os.O_ACCMODE == os.O_RDONLY
        opened = Path(os.fsdecode(path)).resolve()
        if not reading or opened.parent != self.folder or opened.name not in RUN_FILES:
            return
        self.reads += 1
        reader = next((room for room in reversed(self.stack) if room and room not in GROUND), "")
        if not self.rooms or self.rooms[-1] != reader:
            self.rooms.append(reader)

    def __enter__(self) -> Walk:
        sys.addaudithook(self.audit)  # audit hooks stay for the process: idle once the walk ends
        self.tracing = True
        sys.setprofile(self.profile)
        return self

    def __exit__(self, *exc: object) -> None:
        sys.setprofile(None)
        self.tracing = False


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory, mini_root) -> Path:
    """A run of the centre baseline over the hand-made set (two runs, the official and the
    diagnosing scorers, parsed leniently): config, rows, summary and transcripts."""
    folder = tmp_path_factory.mktemp("walk")
    pipeline = folder / "pipeline.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)}, "backend": {"name": "center"}, "strategy": "basic", "parser": "json",
        "scorers": ["official", "diagnose"], "runs": 2, "output": str(folder / "run"),
    }), encoding="utf-8")  # fmt: skip
    result = CliRunner().invoke(app, ["run", str(pipeline)])
    assert result.exit_code == 0, result.output
    return folder / "run"


def test_a_report_reads_the_run_folder_from_one_room_entered_once(finished_run, tmp_path):
    with Walk(finished_run) as walk:
        write_report(finished_run, tmp_path / "report", n_boot=20, gallery=True)
    assert walk.reads >= 4  # config, rows indexed, rows read, summary (and the gallery's transcripts)
    assert len(walk.rooms) == len(set(walk.rooms)), walk.rooms  # no room entered twice
    assert walk.rooms == ["results"]


def test_rescore_reads_the_run_folder_from_the_same_room(finished_run):
    with Walk(finished_run) as walk:
        rescore_run(finished_run, "official")
    assert walk.rooms == ["results"]


def test_export_reads_the_run_folder_from_the_same_room(finished_run, tmp_path):
    with Walk(finished_run) as walk:
        export_run(finished_run, tmp_path / "official.json")
        export_long_csv(finished_run, tmp_path / "long.csv")
    assert walk.rooms == ["results"]


def test_compare_reads_the_run_folder_from_the_same_room(finished_run):
    with Walk(finished_run) as walk:
        compare_runs(finished_run, finished_run, n_boot=20)
    assert walk.rooms == ["results"]


def test_the_walk_charges_a_read_to_the_room_that_asked_for_it(tmp_path):
    (tmp_path / "results.jsonl").write_text("", encoding="utf-8")
    (tmp_path / "summary.json").write_text("{}", encoding="utf-8")
    with Walk(tmp_path) as walk:
        (tmp_path / "summary.json").read_bytes()  # this test's own code: no room of povagent
        (tmp_path / "summary.json").write_text("{}", encoding="utf-8")  # a write is no read
        assert FinishedRun.open(tmp_path).declared == {}
    assert walk.rooms == ["", "results"] and walk.reads == 3  # the test's read, the results file checked, the summary
