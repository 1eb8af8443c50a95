"""The parser corpus: realistic answers per model family, each with the parse it must give.

``corpus.yaml`` holds the cases (clean, fenced, chatty, self-correcting, truncated, out of range,
wrong keys, several images, empty ...); one parametrized test checks each through the parser
registered under its name, exactly as a run would create it.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from povagent.answers.spec import AnswerSpec, ParseStatus, frame_answer_schema, point_answer_schema
from povagent.plugins import build_plugin_host

# libyaml's loader where PyYAML was built with it: the same corpus, read ~8x faster (every
# xdist worker reads it while collecting)
CORPUS = yaml.load((Path(__file__).parent / "corpus.yaml").read_text(encoding="utf-8"), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


@pytest.fixture(scope="module")
def host():
    return build_plugin_host(entry_points=False)


def spec_for(case: dict) -> AnswerSpec:
    w, h = case.get("width", 512), case.get("height", 512)
    if case.get("condition", "a") == "c":
        return AnswerSpec(schema=point_answer_schema(w, h), width=w, height=h, n_frames=1, asks_frame=False)
    n = case.get("frames", 30)
    return AnswerSpec(schema=frame_answer_schema(n, w, h), width=w, height=h, n_frames=n, asks_frame=True)


def test_corpus_is_large_and_covers_every_family():
    families = {c["parser"] for c in CORPUS}
    assert len(CORPUS) >= 60
    assert families == {"json", "cot", "rescale-1000", "qwen", "gemini", "molmo", "robopoint", "internvl"}
    assert len({c["id"] for c in CORPUS}) == len(CORPUS)


def test_every_family_has_answers_and_non_answers():
    for family in {c["parser"] for c in CORPUS}:
        statuses = {c["expect"]["status"] for c in CORPUS if c["parser"] == family}
        assert {"ok", "unparseable"} <= statuses, family
        assert statuses & {"out_of_range", "repaired"}, family


@pytest.mark.parametrize("case", CORPUS, ids=[c["id"] for c in CORPUS])
def test_parse_matches_expected(case, host):
    parsed = host.create("parser", case["parser"], {}).parse(case["text"], spec_for(case))
    want = case["expect"]
    assert parsed.status == ParseStatus(want["status"]), parsed.reason
    if want["status"] == "unparseable":
        assert parsed.x is None and parsed.y is None and parsed.reason
        return
    assert parsed.selected_image == want.get("selected_image")
    assert parsed.x == pytest.approx(want["x"], abs=1e-6)
    assert parsed.y == pytest.approx(want["y"], abs=1e-6)
    assert parsed.span, "the raw span the answer came from is kept"
    n_points = want.get("n_points")
    assert (len(parsed.points) if parsed.points else 1) == (n_points or 1)
    if want["status"] == "repaired":
        assert parsed.repair
    else:
        assert parsed.repair is None
