"""Official vs lenient parsing, measured: agreement on the answer corpus and response rates of a replayed run.

Two measurements:

1. **Agreement per answer.** Every JSON answer of ``tests/parsers/official_corpus.yaml`` (the
   realistic answers with the outcome the official runner gives each) is parsed with the
   ``official`` parser and with each lenient one; an answer agrees when both leave it unanswered,
   or both read the same frame and point (NaN equal to NaN).
2. **A replayed run.** A synthetic release (``povagent.testing.pytest_plugin.write_release``, 30 frames per
   house as in the real release) gets one answer per instance, drawn with a fixed seed from the
   corpus answers of its condition (A/B answers for Inferred and Stated, C answers for Given);
   answers whose official reading has a NaN or infinite coordinate are left out, so the means are
   means; the run is replayed through the ``replay`` backend with a lenient parser, so its summary
   carries the repaired numbers and, beside them, the official parse's (recorded per row);
   ``rescore RUN --parser official`` is checked to give the same official numbers offline.

The corpus is made of edge cases on purpose (about half of its answers are ones the official
runner leaves unanswered), so the rates below measure how differently the parsers treat such
answers, not how often a given model writes them.

Usage::

    python benchmarks/official_vs_lenient.py [--houses 6] [--seed 0] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import random
import sys
import tempfile
from pathlib import Path

import yaml

REPO = Path(__file__).resolve().parents[1]
CORPUS = REPO / "tests" / "parsers" / "official_corpus.yaml"
LENIENT = ("json", "cot", "rescale-1000")


def _same(a, b) -> bool:
    if a is None or b is None:
        return a is b
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def agreement(host, cases) -> dict[str, tuple[int, int]]:
    """Per lenient parser: (answers agreeing with official, answers)."""
    from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema

    out = {}
    official = host.create("parser", "official", {})
    for name in LENIENT:
        parser = host.create("parser", name, {})
        agree = 0
        for case in cases:
            if case.get("condition", "a") == "c":
                spec = AnswerSpec(schema=point_answer_schema(512, 512), n_frames=1, asks_frame=False)
            else:
                spec = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
            a, b = official.parse(case["text"], spec), parser.parse(case["text"], spec)
            scored_a = a.answered and (not spec.asks_frame or (a.selected_image is not None and 0 <= a.selected_image < 30))
            scored_b = b.answered and (not spec.asks_frame or (b.selected_image is not None and 0 <= b.selected_image < 30))
            if scored_a == scored_b and (not scored_a or (_same(a.x, b.x) and _same(a.y, b.y) and a.selected_image == b.selected_image)):
                agree += 1
        out[name] = (agree, len(cases))
    return out


def replayed_run(out: Path, cases, houses: int, seed: int) -> list[tuple[str, dict, dict]]:
    """Replay one corpus answer per instance with each lenient parser; returns (parser, summary,
    official summary from rescore)."""
    from povagent.config.models import PipelineConfig
    from povagent.dataset.instances import row_key
    from povagent.dataset.loader import load_dataset
    from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus
    from povagent.run.rescore import rescore_run
    from povagent.run.runner import run_pipeline
    from povagent.testing.pytest_plugin import write_release

    release = write_release(out / "release", houses=houses, frames=30)
    dataset = load_dataset(release)
    rng = random.Random(seed)
    # answers whose official reading holds a non-finite coordinate are left out of the replay:
    # NaN makes every official mean holding it NaN (tested on its own), and infinity is scored
    # at the edge only by a scorer that clamps it; the rates below stay comparable either way
    finite = [c for c in cases if c["official"] == "none" or all(math.isfinite(c["official"][k]) for k in ("x", "y"))]
    by_condition = {"ab": [c["text"] for c in finite if c.get("condition", "a") != "c"], "c": [c["text"] for c in finite if c.get("condition") == "c"]}
    source = out / "answers"
    source.mkdir(parents=True, exist_ok=True)
    with ResultsWriter(source / "results.jsonl") as writer:
        for inst in dataset.instances():
            raw = rng.choice(by_condition["c" if str(inst.condition) == "c" else "ab"])
            writer.write(ResultRow(
                key=row_key(inst.id, 0), instance_id=inst.id, house_id=inst.house_id, pair_id=inst.pair_id,
                direction=str(inst.direction), condition=str(inst.condition), status=RowStatus.ANSWERED,
                exchanges=[ExchangeRecord(request_hash="corpus", raw=raw)],
            ))
    results = []
    for parser in LENIENT:
        config = PipelineConfig.model_validate({
            "dataset": {"path": str(release)},
            "backend": {"name": "replay", "options": {"path": str(source)}},
            "strategy": "basic",
            "parser": parser,
            "scorers": ["official"],
            "concurrency": 8,
            "output": str(out / f"run-{parser}"),
        })
        run = run_pipeline(config)
        rescored = rescore_run(run.run_dir, "official")
        # the summaries as their files hold them
        results.append((parser, json.loads((run.run_dir / "summary.json").read_text()), json.loads((rescored.out_dir / "summary.json").read_text())))
        for w in rescored.warnings:
            print(f"  ({parser}) warning: {w[:160]}...")
    return results


def _rate(cell) -> str:
    return "-" if cell["response_rate"] is None else f"{100 * cell['response_rate']:.1f}%"


def _l2(cell) -> str:
    return "-" if cell["mean_l2"] is None else f"{cell['mean_l2']:.3f}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--houses", type=int, default=6)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args(argv)
    from povagent.plugins import build_plugin_host

    cases = [c for c in yaml.safe_load(CORPUS.read_text(encoding="utf-8")) if c.get("parser", "official") == "official"]
    host = build_plugin_host(entry_points=False)
    print(f"Agreement with the official runner on {len(cases)} corpus answers:")
    for name, (agree, n) in agreement(host, cases).items():
        print(f"  {name:13s} {agree}/{n}")
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        rows = replayed_run(out, cases, args.houses, args.seed)
        print(f"\nReplayed run ({args.houses} synthetic houses, one corpus answer per instance, seed {args.seed}):")
        print(
            "| parser | rows | resp. rate (repaired) | mean L2 (repaired) | resp. rate (official parse) | mean L2 (official parse) | rescore --parser official "
            "agrees |"
        )
        print("|---|---|---|---|---|---|---|")
        for parser, summary, rescored in rows:
            mine, official = summary["overall"], summary["official_parse"]["overall"]
            same = rescored["overall"]["n"] == official["n"] and rescored["overall"]["n_total"] == official["n_total"]
            print(f"| {parser} | {mine['n_total']} | {_rate(mine)} | {_l2(mine)} | {_rate(official)} | {_l2(official)} | {'yes' if same else 'NO'} |")
            for c, cell in summary["per_condition"].items():
                o = summary["official_parse"]["per_condition"][c]
                print(f"|   {c.upper()} | {cell['n_total']} | {_rate(cell)} | {_l2(cell)} | {_rate(o)} | {_l2(o)} | |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
