"""Run as a script by ``test_directions.py``: add a fifth direction to the registry (one edit to
its source, the one a maintainer would make) and run the quickstart on it: generation, ground
truth, scoring, the report's filter and the breakdown take it with no other edit.

The edited registry is installed before any other povagent module is imported, as if the file
had been edited; nothing is written into the package. Prints one JSON line of what it saw.
"""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path

import povagent

#: The fifth direction: on the far side of the anchor from the observer, beside it on its surface.
BEHIND = '''
DIRECTION_REGISTRY += (
    DirectionSpec(
        name="behind",
        paper_words="behind",
        prompt_word="BEHIND",
        short_words="behind",
        synonyms=("back",),
        sentence_phrase="behind the {anchor}",
        on_anchor_phrase=None,
        seat_phrase=None,
        placement=Placement.BESIDE,
        axis=(Axis.FORWARD, 1.0),
        may_stand_on_anchor=False,
        mirror="behind",
    ),
)
'''
#: Where the edit goes: right after the registry's closing parenthesis.
MARKER = "\n#: The fields the generator's output depends on"


def install_edited_registry() -> None:
    path = Path(povagent.__file__).parent / "geometry" / "directions.py"
    source = path.read_text(encoding="utf-8")
    if MARKER not in source:
        raise SystemExit(f"the registry's end marker is gone from {path}")
    module = types.ModuleType("povagent.geometry.directions")
    module.__file__ = str(path)
    sys.modules[module.__name__] = module
    exec(compile(source.replace(MARKER, BEHIND + MARKER, 1), str(path), "exec"), module.__dict__)


def main(out: Path) -> None:
    install_edited_registry()
    import numpy as np

    from povagent.dataset.release_models import DIRECTIONS
    from povagent.geometry.ground_truth import AnchorBox, target_point
    from povagent.report.quickstart import run_quickstart

    box = AnchorBox(center_xz=(0.0, 0.0), half_xz=(0.5, 0.3), top=0.8)
    # observer at z = -3 looking at the anchor: "behind" is the anchor's far side, +z
    gt = target_point("behind", box, "Sofa", np.zeros(3), np.array([0.0, 1.5, -3.0]), "appropriate", "on the floor", np.zeros(3))
    # seed 5: its first house has "behind" pairs and is about a third of seed 0's (the
    # default) to make: this child costs about 4 s of CPU in all, against 6.7 s with seed 0
    result = run_quickstart(out, houses=1, seed=5, frames=2, jobs=1, quiet=True, say=lambda _: None)
    pairs = [p for f in sorted((result.dataset / "artifacts").glob("*/train_house_*.json")) for p in json.loads(f.read_text())]
    rows = [json.loads(line) for f in sorted(result.sweep.glob("*/results.jsonl")) for line in f.read_text().splitlines() if line]
    page = result.report.read_text(encoding="utf-8")
    tables = (result.report.parent / "tables.md").read_text(encoding="utf-8")
    print(json.dumps({
        "directions": [str(d) for d in DIRECTIONS],
        "gt": [round(float(v), 6) for v in gt],
        "given_sentences": [p["stage6"]["behind"]["type_c"] for p in pairs if "behind" in p["stage6"]],
        "oracle_l2": [r["scores"]["official"]["l2"] for r in rows if r["backend"] == "oracle" and r["direction"] == "behind"],
        "page_has_filter_option": "<option>behind</option>" in page,
        "direction_header": next(line for line in tables.splitlines() if line.startswith("| Baseline | Right")),
    }))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
