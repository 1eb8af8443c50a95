"""Check the prompt boxes copied into the repository against the paper's own LaTeX source.

Run: ``python benchmarks/paper_fidelity.py [--tex PATH]``. ``tests/prompts/paper_prompts.tex`` is
the appendix "Evaluation Prompts" copied verbatim from the paper, and the test suite checks the
prompt templates against that copy; this script checks the copy against the paper itself, which
only the project's maintainers have (``../shared/seed/contextual-observer-grounding.tex`` beside
the clone, by default). It lives here rather than in the test suite so a user's ``pytest`` never
skips a test over a file they cannot have; CI runs it where the source is present.

Exit codes: 0 every box and the placeholder sentence are byte-identical; 1 one differs (named);
2 the paper's source is not there.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COPY = ROOT / "tests" / "prompts" / "paper_prompts.tex"
PAPER = ROOT.parent / "shared" / "seed" / "contextual-observer-grounding.tex"

#: The appendix's prompt boxes, by the paragraph heading that precedes each.
HEADINGS = {
    "basic-frames": "\\paragraph{Basic prompt (Inferred / Stated).}",
    "basic-given": "\\paragraph{Basic prompt (Given).}",
    "cot": "\\paragraph{CoT prompt (Inferred / Stated).}",
    "spatial-step4": "\\paragraph{Spatial-CoT prompt (Inferred / Stated).}",
}

#: The sentence that introduces the placeholders, in both files.
INTRO = "Placeholders (\\textit{N} images, the task \\textit{sentence}, and image size $W\\times H$) are filled at runtime."


def box_after(tex: str, heading: str) -> str:
    """The body of the first ``tcolorbox`` after ``heading``."""
    start = tex.index(heading)
    begin = tex.index("\\begin{tcolorbox}", start)
    body_start = tex.index("\n", begin) + 1
    return tex[body_start : tex.index("\\end{tcolorbox}", body_start)]


def differences(copy: str, paper: str) -> list[str]:
    """The boxes (and the placeholder sentence) that are not byte-identical, by name."""
    out = []
    for name, heading in HEADINGS.items():
        try:
            if box_after(copy, heading) != box_after(paper, heading):
                out.append(f"box {name!r} differs")
        except ValueError:
            out.append(f"box {name!r} missing from one of the files")
    if INTRO not in copy or INTRO not in paper:
        out.append("the placeholder sentence differs")
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tex", type=Path, default=PAPER, help=f"the paper's LaTeX source (default: {PAPER})")
    args = parser.parse_args(argv)
    if not args.tex.is_file():
        print(f"paper_fidelity: the paper's source is not at {args.tex}", file=sys.stderr)
        return 2
    found = differences(COPY.read_text(encoding="utf-8"), args.tex.read_text(encoding="utf-8"))
    for line in found:
        print(f"paper_fidelity: {COPY.relative_to(ROOT)}: {line} from {args.tex}", file=sys.stderr)
    if not found:
        print(f"paper_fidelity: {len(HEADINGS)} prompt boxes and the placeholder sentence are the paper's, byte for byte")
    return 1 if found else 0


if __name__ == "__main__":
    raise SystemExit(main())
