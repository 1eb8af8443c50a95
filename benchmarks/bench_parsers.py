"""Parser speed: the test corpus parsed repeatedly, and what caching the schema validator saves.

Run: ``python benchmarks/bench_parsers.py``. Prints answers per second per parser; the ratio of
validating with the cached validator against checking and compiling the schema per call, the
work the cache saves (the design rule: no per-call compilation on the hot path); and the time of
the slowest parser on hostile answers of a few hundred kilobytes (each must stay linear).
"""

from __future__ import annotations

import time
from pathlib import Path

import yaml
from jsonschema import Draft202012Validator

from povagent.answers.spec import AnswerSpec, frame_answer_schema, point_answer_schema
from povagent.answers.validation import validator_for
from povagent.plugins import build_plugin_host

CORPUS = yaml.safe_load((Path(__file__).resolve().parents[1] / "tests" / "parsers" / "corpus.yaml").read_text(encoding="utf-8"))
FRAMES = AnswerSpec(schema=frame_answer_schema(30, 512, 512), n_frames=30)
GIVEN = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)


def per_second(fn, n: int) -> float:
    start = time.perf_counter()
    for _ in range(n):
        fn()
    return n / (time.perf_counter() - start)


def elapsed(fn) -> float:
    """Seconds one call of ``fn`` takes."""
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    host = build_plugin_host(entry_points=False)
    cases = [(c["parser"], c["text"], GIVEN if c.get("condition") == "c" else FRAMES) for c in CORPUS]
    parsers = {name: host.create("parser", name, {}) for name in {c[0] for c in cases}}
    for name in sorted(parsers):
        mine = [(t, s) for p, t, s in cases if p == name]
        # the lambda runs within this iteration: it sees this iteration's name and cases
        rate = per_second(lambda: [parsers[name].parse(t, s) for t, s in mine], 200) * len(mine)  # noqa: B023
        print(f"{name:14s} {rate:10.0f} answers/s  ({len(mine)} corpus cases)")

    answer = {"selected_image": 3, "x": 100, "y": 200}
    cached = per_second(lambda: list(validator_for(FRAMES.json_schema).iter_errors(answer)), 5000)

    def uncached() -> None:
        Draft202012Validator.check_schema(FRAMES.json_schema)
        list(Draft202012Validator(FRAMES.json_schema).iter_errors(answer))

    compiled = per_second(uncached, 500)
    print(f"validate with cached validator: {cached:.0f}/s; check + compile per call: {compiled:.0f}/s; ratio {cached / compiled:.1f}x")

    hostile = {
        "400 kB of empty objects": "{}" * 200_000,
        "10 kB of nested braces": "{" * 5000 + '"x": 1' + "}" * 5000,
        "100 kB of unclosed <box> tags": "<box>" * 20_000,
        "700 kB of 100k small objects": '{"a":1}' * 100_000,
    }
    for label, text in hostile.items():
        # each lambda runs at once, inside the generator step that made it
        seconds, name = max((elapsed(lambda: parser.parse(text, FRAMES)), name) for name, parser in parsers.items())  # noqa: B023
        print(f"hostile, {label:31s} slowest parser {name:13s} {seconds * 1000:7.1f} ms")


if __name__ == "__main__":
    main()
