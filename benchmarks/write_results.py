"""Write ``benchmarks/RESULTS.md`` from the benchmarks' JSON outputs (``benchmarks/results/*.json``).

Run: ``python benchmarks/write_results.py [--check]``. Every figure the project publishes is a
row of that page, with the date it was measured, the machine (cores, CPU model, load average),
the command that re-runs it and what it is set beside; the README and the docs state behaviour
and point here for numbers (``tests/test_docs_figures.py`` fails when a figure there has no
source here). The notes on method that the docs carried (how each figure was taken, what a
comparison's peer ran with) are appended from ``benchmarks/notes/*.md``. ``--check`` exits 1
when the page is stale instead of writing it.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
RESULTS_DIR = HERE / "results"
NOTES_DIR = HERE / "notes"
PAGE = HERE / "RESULTS.md"

#: Keys every results file must have (the shape ``results_file.record`` writes).
REQUIRED = ("benchmark", "date", "machine", "command", "figures")


def format_value(value: Any, unit: str) -> str:
    """``0.35x``, ``97.2%``, ``1.3 s``: the figure as the README and docs would write it."""
    if isinstance(value, float) and value.is_integer() and unit not in ("x",):
        value = int(value)
    number = f"{value:,}" if isinstance(value, int) and abs(value) >= 10_000 else str(value)
    return f"{number}{unit}" if unit in ("x", "%") else f"{number} {unit}"


def load(path: Path) -> dict[str, Any]:
    """One results file, checked for the keys of its shape (a clear error naming the file)."""
    doc = json.loads(path.read_text(encoding="utf-8"))
    missing = [k for k in REQUIRED if k not in doc]
    if missing:
        raise SystemExit(f"{path}: missing {', '.join(missing)} (write it with benchmarks/results_file.py)")
    return doc


def _cell(text: Any) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def render(results_dir: Path = RESULTS_DIR, notes_dir: Path = NOTES_DIR) -> str:
    """The page: one section per benchmark (sorted by name), then the notes on method."""
    lines = [
        "# Measured results",
        "",
        "<!-- written by benchmarks/write_results.py from benchmarks/results/*.json; do not edit -->",
        "",
        "Every figure povagent publishes, with when and where it was measured and the command that",
        "re-runs it. Figures marked *carried* were measured before this page existed and are copied",
        "from the README of that date; re-running the command replaces them.",
        "",
    ]
    for path in sorted(results_dir.glob("*.json")):
        doc = load(path)
        m = doc["machine"]
        load_avg = ", ".join(str(x) for x in m.get("load_avg", []))
        lines += [
            f"## {doc['benchmark']}",
            "",
            f"- date: {doc['date']}" + (" (*carried*)" if "carried" in doc.get("note", "") else ""),
            f"- machine: {m.get('cores')} cores, {m.get('cpu_model')}, load average {load_avg}",
            f"- command: `{doc['command']}`",
        ]
        if doc.get("note"):
            lines.append(f"- note: {doc['note']}")
        lines += ["", "| figure | value | target | set beside |", "|---|---|---|---|"]
        for f in doc["figures"]:
            value = format_value(f["value"], f.get("unit", ""))
            lines.append(f"| {_cell(f['name'])} | {_cell(value)} | {_cell(f.get('target', ''))} | {_cell(f.get('comparison', ''))} |")
        lines.append("")
    notes = sorted(notes_dir.glob("*.md")) if notes_dir.is_dir() else []
    if notes:
        lines += ["# Notes on method", "", "How the figures above were taken, as the docs described them.", ""]
        for note in notes:
            body = note.read_text(encoding="utf-8").strip()
            # the notes' headings sit one level under "Notes on method"
            body = "\n".join("#" + line if line.startswith("#") else line for line in body.splitlines())
            lines += [body, ""]
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 when RESULTS.md is stale, write nothing")
    args = parser.parse_args(argv)
    text = render()
    if args.check:
        if not PAGE.exists() or PAGE.read_text(encoding="utf-8") != text:
            print(f"{PAGE} is stale: run python benchmarks/write_results.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(text, encoding="utf-8")
    print(PAGE)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
