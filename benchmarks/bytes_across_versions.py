"""A generated set and a view under the lowest and the highest versions pyproject.toml allows of
what decides their bytes: the same bytes, or which files differ.

    python benchmarks/bytes_across_versions.py [--keep DIR]

Builds a virtual environment per version set (from the package registry, as the README's
install does), installs this checkout into it with the versions named below, and runs
``tests/generate/cpu_bytes_child.py`` there (a one-house set of seed 11 and one rendered view,
every file's SHA-256). The sets: the lowest allowed numpy, SciPy, Pillow, trimesh and embreex
(Embree 4), the same with embreex's Embree 2 build, and the newest of each (what a fresh
install takes today). Figures: files that differ from the newest set's, per version set (goal 0).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from results_file import figure, record

ROOT = Path(__file__).resolve().parent.parent
CHILD = ROOT / "tests" / "generate" / "cpu_bytes_child.py"
#: The version sets (pip requirement strings; empty: the newest the registry serves).
SETS = {
    "newest": [],
    "lowest (Embree 4)": ["numpy==1.26.4", "scipy==1.11.4", "Pillow==10.2.0", "trimesh==4.0.0", "embreex==4.4.0"],
    "lowest, embreex's Embree 2 build": ["numpy==1.26.4", "scipy==1.11.4", "Pillow==10.2.0", "trimesh==4.0.0", "embreex==2.17.7.post7"],
}


def digests(folder: Path, pins: list[str]) -> tuple[dict[str, str], str]:
    """The child's file digests in a fresh environment with ``pins``, and its versions line."""
    venv = folder / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    pip = [str(venv / "bin" / "python"), "-m", "pip", "install", "-q", "--disable-pip-version-check"]
    subprocess.run([*pip, *pins, str(ROOT)], check=True)
    versions = subprocess.run([str(venv / "bin" / "python"), "-c",
                               "import importlib.metadata as m; print(', '.join(f'{p} {m.version(p)}' for p in ('numpy', 'scipy', 'Pillow', 'trimesh', "
                               "'embreex')))"],
                              capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    done = subprocess.run([str(venv / "bin" / "python"), str(CHILD), str(folder / "set")], capture_output=True, text=True, check=True, cwd=folder)
    return json.loads(done.stdout), versions


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--keep", type=Path, help="build the environments here (default: a temporary folder, removed after)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base = args.keep or Path(tmp)
        results = {}
        for k, (name, pins) in enumerate(SETS.items()):
            folder = base / f"set{k}"
            folder.mkdir(parents=True, exist_ok=True)
            results[name] = digests(folder, pins)
            print(f"{name}: {results[name][1]}", flush=True)
    newest = results["newest"][0]
    figures = []
    for name, (files, versions) in results.items():
        if name == "newest":
            continue
        differ = sorted(f for f in newest.keys() | files.keys() if newest.get(f) != files.get(f))
        print(f"{name}: {len(differ)} of {len(newest)} files differ from the newest set's {differ[:5]}")
        figures.append(figure(f"files that differ from the newest versions' ({name})", len(differ), "files", target="0",
                              comparison=f"{versions}; newest: {results['newest'][1]}"))  # fmt: skip
    record("bytes_across_versions", figures)


if __name__ == "__main__":
    main()
