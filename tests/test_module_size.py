"""No module of povagent or of its built-in plugins is over 500 lines: a module is a room with
one job, and one that grows past a few screens has taken a second job that wants its own room.

A module may stand over the limit only while it is listed below with the reason, as a
temporary exception; a listed module that is back under the limit fails too, so the list only
shrinks. The scan reads the files; it imports nothing.

Nor is a module kept under the limit by squeezing: ``ruff format`` lays out every statement but
at most ten hand-laid tables (each kept out of the formatter with a ``# fmt: skip`` marker and a
comment saying why the hand layout reads better), and no ``# fmt: off`` block turns it off.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The most lines a module may have.
LIMIT = 500
#: Modules over the limit for now, each with why it is not split yet (path from the repository root).
TEMPORARY_EXCEPTIONS: dict[str, str] = {}
#: The most statements povagent/ and plugins/ may keep out of the formatter (issue 56).
MAX_FORMAT_SKIPS = 10
#: What a marker's comment starts with: the reason the hand layout is kept.
WHY = "# Laid out by hand"


def modules(root: Path = ROOT) -> dict[str, str]:
    """The text of every module under povagent/ and plugins/, by path from ``root``."""
    return {
        path.relative_to(root).as_posix(): path.read_text(encoding="utf-8")
        for folder in ("povagent", "plugins")
        for path in sorted((root / folder).rglob("*.py"))
    }


def module_lengths() -> dict[str, int]:
    """Lines of every module under povagent/ and plugins/, by path from the repository root."""
    return {path: len(text.splitlines()) for path, text in modules().items()}


def format_skips(texts: dict[str, str]) -> list[tuple[str, int]]:
    """(path, line) of every line that keeps code out of the formatter: a ``# fmt: skip`` marker
    or a ``# fmt: off`` block."""
    return [
        (path, number)
        for path, text in texts.items()
        for number, line in enumerate(text.splitlines(), start=1)
        if line.rstrip().endswith(("# fmt: skip", "# fmt: off")) or line.strip() == "# fmt: off"
    ]


def unexplained_skips(texts: dict[str, str]) -> list[tuple[str, int]]:
    """Markers whose statement carries no comment saying why: a line starting with :data:`WHY`
    inside the statement or on the two lines above it."""
    unexplained = []
    for path, number in format_skips(texts):
        lines = texts[path].splitlines()
        statements = [n for n in ast.walk(ast.parse(texts[path])) if isinstance(n, ast.stmt) and n.lineno <= number <= (n.end_lineno or n.lineno)]
        start = max((n.lineno for n in statements), default=number)
        if not any(line.strip().startswith(WHY) for line in lines[max(start - 3, 0) : number]):
            unexplained.append((path, number))
    return unexplained


def test_no_module_is_over_the_limit_unless_listed_with_a_reason():
    over = {path: n for path, n in module_lengths().items() if n > LIMIT and path not in TEMPORARY_EXCEPTIONS}
    assert over == {}, f"split these modules (one job each) or list them with a reason: {over}"


def compiled_sources(root: Path = ROOT) -> dict[str, int]:
    """Lines of every C source and header of the compiled loops (povagent/generate/), by path."""
    return {path.relative_to(root).as_posix(): len(path.read_text(encoding="utf-8").splitlines()) for path in sorted((root / "povagent").rglob("*.[ch]"))}


def test_no_c_file_of_the_compiled_loops_is_over_the_limit_either():
    sources = compiled_sources()
    assert sources, "the compiled loops' C files were not found"
    over = {path: n for path, n in sources.items() if n > LIMIT}
    assert over == {}, f"split these C files (one job each; setup.py lists what a loop includes): {over}"


def test_every_listed_exception_is_still_over_the_limit():
    lengths = module_lengths()
    back_under = [path for path in TEMPORARY_EXCEPTIONS if lengths.get(path, 0) <= LIMIT]
    assert back_under == [], f"no longer over {LIMIT} lines (or gone): remove them from TEMPORARY_EXCEPTIONS: {back_under}"


def test_every_exception_says_why():
    assert all(reason.strip() for reason in TEMPORARY_EXCEPTIONS.values())


def test_at_most_ten_statements_are_kept_out_of_the_formatter():
    skips = format_skips(modules())
    assert len(skips) <= MAX_FORMAT_SKIPS, (
        f"{len(skips)} statements keep ruff format out (at most {MAX_FORMAT_SKIPS}): let it lay them out, "
        f"and split a module that then grows past {LIMIT} lines by concept: {skips}"
    )


def test_every_kept_marker_says_why():
    assert unexplained_skips(modules()) == [], f"say why the hand layout reads better, in a comment starting {WHY!r}"


def test_the_count_finds_markers_and_off_blocks_but_not_prose(tmp_path):
    (tmp_path / "povagent").mkdir()
    (tmp_path / "plugins").mkdir()
    (tmp_path / "povagent" / "table.py").write_text(
        'X = {"a": 1,  "b": 2}  # fmt: skip\n# fmt: off\nY = [1,  2]\n# fmt: on\nZ = "# fmt: skip is a marker"\n', encoding="utf-8"
    )
    (tmp_path / "plugins" / "plain.py").write_text("W = 1\n", encoding="utf-8")
    assert format_skips(modules(tmp_path)) == [("povagent/table.py", 1), ("povagent/table.py", 2)]


def test_a_marker_without_its_reason_is_found_and_one_with_it_is_not(tmp_path):
    texts = {
        "bare.py": "X = {\n    1: 2,\n}  # fmt: skip\n",
        "explained.py": "X = {\n    # Laid out by hand: a table\n    1: 2,\n}  # fmt: skip\n",
        "above.py": "def f():\n    # Laid out by hand: the rows of a matrix\n    return [[1, 0],\n            [0, 1]]  # fmt: skip\n",
    }
    assert unexplained_skips(texts) == [("bare.py", 3)]
