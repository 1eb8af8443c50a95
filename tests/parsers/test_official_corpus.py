"""The official corpus: realistic answers with the outcome the official runner gives each.

``official_corpus.yaml`` holds answers (fences, prose, self-corrections, trailing commas, single
quotes, comments, upper-case keys, ``px`` units, nested extras, ``"image_3"``, ``3.6``,
booleans, ``1e999``, NaN, chain-of-thought, Qwen/Gemini/Molmo/InternVL/RoboPoint formats),
each with what ``mimo-owl/povbench-eval``'s ``run_vlm_eval.py`` records for it, written down by
reading that code. Every case goes through ``povagent parse --parser <name>`` (the real CLI) and
must agree exactly: answered or not, frame, coordinates (NaN and infinity included), points.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.cli import app

# libyaml's loader where PyYAML was built with it: the same corpus, read ~8x faster (every
# xdist worker reads it while collecting)
CORPUS = yaml.load((Path(__file__).parent / "official_corpus.yaml").read_text(encoding="utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
runner = CliRunner()


def parse_with_cli(case: dict) -> dict:
    args = ["parse", "--parser", case.get("parser", "official"), "--condition", case.get("condition", "a"), "--frames", str(case.get("frames", 30))]
    result = runner.invoke(app, args, input=case["text"])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def same_number(got: float | None, want: float) -> bool:
    if got is None:
        return False
    if math.isnan(want):
        return math.isnan(got)
    if math.isinf(want):
        return got == want
    return math.isclose(got, want, rel_tol=0, abs_tol=1e-9)


def test_corpus_is_large_and_varied():
    assert len(CORPUS) >= 60
    assert len({c["id"] for c in CORPUS}) == len(CORPUS)
    outcomes = [c["official"] for c in CORPUS]
    assert sum(o == "none" for o in outcomes) >= 20 and sum(o != "none" for o in outcomes) >= 30
    assert {c.get("condition", "a") for c in CORPUS} == {"a", "c"}


@pytest.mark.parametrize("case", CORPUS, ids=[c["id"] for c in CORPUS])
def test_parse_agrees_with_the_official_runner(case):
    got = parse_with_cli(case)
    want = case["official"]
    if want == "none":
        assert got["status"] == "unparseable", got
        assert got["x"] is None and got["y"] is None and got["reason"]
        return
    assert got["status"] != "unparseable", got
    if "points" in want:
        assert len(got["points"]) == len(want["points"])
        for (gx, gy), (wx, wy) in zip(got["points"], want["points"]):
            assert same_number(gx, wx) and same_number(gy, wy), (got["points"], want["points"])
        wx, wy = want["centroid"]
    else:
        wx, wy = want["x"], want["y"]
    assert same_number(got["x"], wx) and same_number(got["y"], wy), got
    assert got["selected_image"] == want.get("selected_image")
