"""Parser speed: the test corpus parsed repeatedly, and what caching the schema validator saves.

Run: ``python benchmarks/bench_parsers.py``. Prints answers per second per parser and the ratio
of judging with the cached validator against compiling a validator per call (the design rule:
no per-call compilation on the hot path).
"""

from __future__ import annotations

import time
from pathlib import Path

import yaml
from jsonschema import Draft202012Validator

from povagent.answer_validation import judge
from povagent.answers import AnswerSpec, frame_answer_schema, point_answer_schema
from povagent.plugins import build_plugin_host

CORPUS = yaml.safe_load((Path(__file__).resolve().parents[1] / "tests" / "parsers" / "corpus.yaml").read_text(encoding="utf-8"))
FRAMES = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)


def per_second(fn, n: int) -> float:
    start = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - start)


def main() -> None:
    host = build_plugin_host(entry_points=False)
    cases = [(c["parser"], c["text"], GIVEN if c.get("condition") == "c" else FRAMES) for c in CORPUS]
    parsers = {name: host.create("parser", name, {}) for name in {c[0] for c in cases}}
    for name in sorted(parsers):
        mine = [(t, s) for p, t, s in cases if p == name]
        rate = per_second(lambda: [parsers[name].parse(t, s) for t, s in mine], 200) * len(mine)
        print(f"{name:14s} {rate:10.0f} answers/s  ({len(mine)} corpus cases)")

    cached = per_second(lambda: judge(FRAMES, 100, 200, 3), 5000)

    def uncached() -> None:
        list(Draft202012Validator(FRAMES.json_schema).iter_errors({"selected_image": 3, "x": 100, "y": 200}))

    compiled = per_second(uncached, 5000)
    print(f"judge with cached validator: {cached:.0f}/s; compiling per call: {compiled:.0f}/s; ratio {cached / compiled:.1f}x")


if __name__ == "__main__":
    main()
