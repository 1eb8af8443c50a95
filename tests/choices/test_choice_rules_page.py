"""docs/explanation/choice-rules.md carries the tables benchmarks/choice_rules.py counts on the probe
corpus: a count typed by hand, or left stale when the corpus changes, fails here."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def choice_rules_script():
    spec = importlib.util.spec_from_file_location("povagent_bench_choice_rules", ROOT / "benchmarks" / "choice_rules.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_the_page_holds_the_tables_counted_on_the_corpus():
    script = choice_rules_script()
    page = script.PAGE.read_text(encoding="utf-8")
    tables = script.render(yaml.safe_load(script.CORPUS.read_text(encoding="utf-8")))
    assert script.page_with(page, tables) == page, "run: python benchmarks/choice_rules.py --write"


def test_the_tables_count_disagreements_from_the_corpus_labels():
    script = choice_rules_script()
    replies = [
        {"id": "a", "answer": "x", "labels": dict.fromkeys(script.RULES, "A"), "official_code": {"viewspatial": "A", "mindcube": "A"},
         "bugs": [], "compute_mcq_score_hit": {"G": 0}, "sparbench_exact_match_hit": {"B": 0}},
        {"id": "b", "answer": "y", "labels": {**dict.fromkeys(script.RULES, "B"), "mindcube": None},
         "official_code": {"viewspatial": "B", "mindcube": "B"}, "bugs": [], "compute_mcq_score_hit": {"G": 0},
         "sparbench_exact_match_hit": {"B": 1}},
    ]  # fmt: skip
    tables = script.render({"replies": replies})
    assert "| `mindcube` | " in tables and "| 1 of 2 | 1, -, 1, 1, 1, 1 |" in tables
    assert "| `mll-lab-nu/MindCube @ " not in tables and "mll-lab-nu/MindCube @ `6d8fd9acdf5b` | 1 of 2 |" in tables
