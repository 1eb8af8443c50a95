"""The tables of docs/explanation/choice-rules.md, counted on the multiple-choice probe corpus.

Run: ``python benchmarks/choice_rules.py`` prints the tables; ``--write`` puts them in the page
between its markers (tests/choices/test_choice_rules_page.py holds the page equal to this
output). Every count comes from tests/choices/mcq_corpus.yaml, whose labels were produced by
running the upstream rules at their pinned commits; nothing here is typed by hand.
"""

from __future__ import annotations

import sys
from itertools import combinations
from pathlib import Path

import yaml

from povagent_plugins.parsers.mcq.upstream import LMMS_EVAL, MINDCUBE, VIEWSPATIAL_BENCH, VLMEVALKIT

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT / "tests" / "choices" / "mcq_corpus.yaml"
PAGE = ROOT / "docs" / "explanation" / "choice-rules.md"
BEGIN = "<!-- choice-rules tables: python benchmarks/choice_rules.py --write -->\n"
END = "<!-- end choice-rules tables -->"

#: Each rule parser: the upstream rule it reproduces and the commit (``repo@sha``) it follows.
RULES = {
    "viewspatial": ("reasoning-tag strip, then `lmms_eval/tasks/viewspatial/utils.py` `extract_option`", LMMS_EVAL),
    "mindcube": ("reasoning-tag strip, then `lmms_eval/tasks/mindcube/utils.py` `extract_answer`", LMMS_EVAL),
    "3dsrbench-lmms": ("reasoning-tag strip, then `lmms_eval/tasks/3dsrbench/utils.py` `extract_answer`", LMMS_EVAL),
    "vlmevalkit-exact": ("`vlmeval/utils/matching_util.py` `can_infer`, else `Z`", VLMEVALKIT),
    "vlmevalkit-spatial": ("`vlmeval/dataset/utils/spatial_bench/matching_func.py` `can_match_option`", VLMEVALKIT),
    "lmms-mcq-extract": ("`lmms_eval/tasks/_task_utils/mcq_extract.py` `extract_mcq_answer`", LMMS_EVAL),
}
#: The sets' own scripts, beside the lmms-eval ports the parsers follow.
OWN_SCRIPTS = {"viewspatial": VIEWSPATIAL_BENCH, "mindcube": MINDCUBE}


def _commit(pinned: str) -> str:
    repository, sha = pinned.split("@")
    return f"{repository} @ `{sha[:12]}`"


def render(corpus: dict) -> str:
    """The page's tables for ``corpus`` (the parsed mcq_corpus.yaml)."""
    replies = corpus["replies"]
    total = len(replies)
    names = list(RULES)

    def differ(a: str, b: str) -> int:
        return sum(1 for r in replies if r["labels"][a] != r["labels"][b])

    lines = [
        f"Counts are over the {total} probe replies of `tests/choices/mcq_corpus.yaml` (options A=right, B=left, "
        "C=front, D=back).",
        "",
        "| parser | upstream rule | commit | no label | replies read differently from: " + ", ".join(f"`{n}`" for n in names) + " |",
        "|---|---|---|---|---|",
    ]
    for name in names:
        rule, pinned = RULES[name]
        none = sum(1 for r in replies if r["labels"][name] is None)
        others = ", ".join("-" if other == name else str(differ(name, other)) for other in names)
        lines.append(f"| `{name}` | {rule} | {_commit(pinned)} | {none} of {total} | {others} |")
    agree_all = sum(1 for r in replies if len(set(r["labels"].values())) == 1)
    pairs = sum(1 for a, b in combinations(names, 2) if differ(a, b))
    lines += [
        "",
        f"All six rules give the same label to {agree_all} of the {total} replies; {pairs} of the "
        f"{len(list(combinations(names, 2)))} pairs of rules disagree somewhere.",
        "",
        "| the set's own script | commit | replies it reads differently from the lmms-eval port |",
        "|---|---|---|",
    ]
    for name, pinned in OWN_SCRIPTS.items():
        count = sum(1 for r in replies if r["official_code"][name] != r["labels"][name])
        lines.append(f"| `{name}` | {_commit(pinned)} | {count} of {total} |")
    tagged = {tag: sum(1 for r in replies if tag in r["bugs"]) for tag in ("lmms-mcq-extract-phrase", "sparbench-empty")}
    false_hits = sum(1 for r in replies if r["compute_mcq_score_hit"]["G"])
    spar_gold_b = sum(1 for r in replies if r["sparbench_exact_match_hit"]["B"])
    spar_bug_b = sum(
        1 for r in replies if r["sparbench_exact_match_hit"]["B"] and {"sparbench-empty", "sparbench-first-character"} & set(r["bugs"])
    )
    lines += [
        "",
        "| known bug | upstream reading | corrected reading | replies where it fires |",
        "|---|---|---|---|",
        f"| \"The answer is C. Because...\" reads B | `lmms-mcq-extract` | `lmms-mcq-extract-corrected` | "
        f"{tagged['lmms-mcq-extract-phrase']} of {total} |",
        f"| no letter on either side is a hit | scorer `choice-vlmevalkit` | scorer `choice-vlmevalkit-corrected` | "
        f"{false_hits} of {total} hits on a gold `G`, all of them replies naming no letter |",
        f"| an empty reply, or one opening with the gold letter, is a hit | `sparbench-lmms` + scorer `choice-sparbench` | "
        f"`sparbench-lmms-corrected` + scorer `choice` | {spar_bug_b} of the {spar_gold_b} hits on a gold `B` "
        f"({tagged['sparbench-empty']} empty replies) |",
    ]
    return "\n".join(lines) + "\n"


def page_with(page: str, tables: str) -> str:
    """``page`` with the text between its markers replaced by ``tables``."""
    head, found, rest = page.partition(BEGIN)
    if not found or END not in rest:
        raise SystemExit(f"{PAGE}: the markers {BEGIN.strip()} ... {END} are missing")
    return head + BEGIN + tables + END + rest.split(END, 1)[1]


def main(argv: list[str]) -> None:
    """Print the tables, or write them into the page with ``--write``."""
    tables = render(yaml.safe_load(CORPUS.read_text(encoding="utf-8")))
    if "--write" in argv:
        PAGE.write_text(page_with(PAGE.read_text(encoding="utf-8"), tables), encoding="utf-8")
        print(f"{PAGE.relative_to(ROOT)}: tables rewritten")
    else:
        print(tables, end="")


if __name__ == "__main__":
    main(sys.argv[1:])
