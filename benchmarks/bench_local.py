"""The in-process ``transformers`` backend on a tiny checkpoint: batching, memory, first answer.

What it measures, on a tiny Qwen2-VL-style checkpoint built here with random weights
(:mod:`povagent.testing.tiny_checkpoints`: hidden size 32, ``--layers`` layers, 28-56 px images):

* requests/s answering ``--requests`` distinct requests (two labelled images and a sentence
  each, ``--max-tokens`` new tokens, greedy) sent at once, with ``max_batch`` 1 and 8, and
  the ratio; the answers of both must be identical (else the script fails);
* time to first answer: from a fresh backend's ``start()`` (loading the checkpoint) to its
  first answer;
* memory: resident set before loading, after loading, and the process's peak.

Rounds alternate the two settings (the machine is shared); the speed-up is the median of the
per-round ratios, reported with the per-round rates and the load average, in wall time and in
CPU time (``time.process_time``, every thread: the figure the machine's other load moves
least). ``--frames 30 --frame-size 512`` gives each request the dataset's 30 frames of 512x512 (A/B):
batching then gains far less, as decoding and resizing each image (not batched) dominates.

What a GPU run should show: on a CPU a tiny model is bound by Python overhead per ``generate``
step, so batching gains what it saves in per-step overhead; on a GPU an 8B model's decoding is
bound by reading the weights once per step, shared by the whole batch, so ``max_batch`` 8
should answer several times more requests per second than 1 until the batch's activations and
KV cache fill the memory (then the backend splits batches: the ``splits`` count). Run it there
with ``--checkpoint Qwen/Qwen3-VL-8B-Instruct --dtype bfloat16 --device-map auto --requests 64
--max-tokens 256`` (the checkpoint must be in the local Hugging Face cache or downloadable).

Usage: ``python benchmarks/bench_local.py [--requests 32] [--rounds 3] [--max-tokens 16]``.
Writes ``benchmarks/results/bench_local.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from PIL import Image
from results_file import record

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart

HERE = Path(__file__).resolve().parent


def rss_mib() -> float:
    """The process's resident set now, in MiB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def peak_mib() -> float:
    """The process's peak resident set, in MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def make_requests(store: ImageStore, n: int, max_tokens: int, frames: int = 2, size: tuple[int, int] = (64, 48)) -> list[Request]:
    """``n`` distinct requests, ``frames`` labelled images of ``size`` each, as the basic strategy lays them out."""
    out = []
    for i in range(n):
        parts: list[Any] = []
        for k in range(frames):
            image = store.add_pil(Image.new("RGB", size, ((37 * i) % 256, (91 * k) % 256, 30)))
            parts += [TextPart(f"Image {k}:"), ImagePart(image.image_hash)]
        parts.append(TextPart(f"Sentence: the mug {i} is left of the sofa. Output ONLY valid JSON, no other text."))
        spec = AnswerSpec(schema=frame_answer_schema(frames, 512, 512), n_frames=frames, asks_frame=True)
        out.append(Request((Message("user", tuple(parts)),), spec, GenerationParams(max_tokens=max_tokens)))
    return out


async def answer_all(
    options: dict[str, Any], batch: list[Request], store: ImageStore, trust: bool = False
) -> tuple[list[str], float, float, Any, float]:
    """(answers, seconds for the batch after loading, seconds from start to the first answer, stats,
    CPU seconds for the batch after loading: every thread of the process); ``trust``: the
    checkpoint's own code may run (granted as the Python call grants it)."""
    from povagent.config.remote_code import remote_code_granted
    from povagent_plugins.backends.transformers_backend import TransformersBackend

    with remote_code_granted(trust):
        backend = TransformersBackend(**options)
    started = time.perf_counter()
    try:
        await backend.start()
        first = await backend.complete(batch[0], store)
        to_first = time.perf_counter() - started
        t0, c0 = time.perf_counter(), time.process_time()
        responses = await asyncio.gather(*(backend.complete(r, store) for r in batch[1:]))
        seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
        return [first.text] + [r.text for r in responses], seconds, to_first, backend.batch_stats, cpu
    finally:
        await backend.aclose()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--requests", type=int, default=33, help="requests per round (the first is the time-to-first-answer one)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--max-tokens", type=int, default=16)
    parser.add_argument("--frames", type=int, default=2, help="images per request (the dataset's A/B requests show 30)")
    parser.add_argument("--frame-size", type=int, default=None, help="square images of this side (the dataset's: 512); default 64x48")
    parser.add_argument("--layers", type=int, default=2)
    parser.add_argument("--checkpoint", default=None, help="a checkpoint to measure instead of the tiny one")
    parser.add_argument("--dtype", default="auto")
    parser.add_argument("--device-map", default=None)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "bench_local.json")
    args = parser.parse_args()

    before_load = rss_mib()
    with tempfile.TemporaryDirectory() as tmp:
        if args.checkpoint is None:
            from povagent.testing.tiny_checkpoints import build_qwen2_vl

            checkpoint = str(build_qwen2_vl(Path(tmp) / "qwen2_vl", layers=args.layers))
            trust = True  # the tiny folder's processor is remote code (see tiny_checkpoints)
        else:
            checkpoint, trust = args.checkpoint, False
        store = ImageStore()
        size = (args.frame_size, args.frame_size) if args.frame_size else (64, 48)
        batch = make_requests(store, args.requests, args.max_tokens, args.frames, size)
        base = {"model": checkpoint, "dtype": args.dtype, "device_map": args.device_map}
        rates: dict[int, list[float]] = {1: [], 8: []}
        cpu_rates: dict[int, list[float]] = {1: [], 8: []}
        firsts: list[float] = []
        answers: dict[int, list[str]] = {}
        after_load = 0.0
        splits = 0
        for round_ in range(args.rounds):
            for max_batch in (1, 8) if round_ % 2 == 0 else (8, 1):
                texts, seconds, to_first, stats, cpu = asyncio.run(answer_all({**base, "max_batch": max_batch}, batch, store, trust))
                rates[max_batch].append((len(batch) - 1) / seconds)
                cpu_rates[max_batch].append((len(batch) - 1) / cpu)
                firsts.append(to_first)
                splits += stats.splits if stats is not None else 0
                after_load = max(after_load, rss_mib())
                if max_batch in answers and answers[max_batch] != texts:
                    print("answers changed between rounds", file=sys.stderr)
                    return 1
                answers[max_batch] = texts
        if answers[1] != answers[8]:
            print("max_batch 8 answered differently from max_batch 1", file=sys.stderr)
            return 1
    r1, r8 = statistics.median(rates[1]), statistics.median(rates[8])
    # the ratio is taken within each round (the load changes between rounds), then the median
    ratio = statistics.median(b / a for a, b in zip(rates[1], rates[8]))
    # CPU time is what the machine's other load moves least: the speed-up in requests per CPU-second
    c1, c8 = statistics.median(cpu_rates[1]), statistics.median(cpu_rates[8])
    cpu_ratio = statistics.median(b / a for a, b in zip(cpu_rates[1], cpu_rates[8]))
    load = list(os.getloadavg())
    print(
        f"requests/s  max_batch 1: {r1:.2f}  max_batch 8: {r8:.2f}  ratio {ratio:.2f}x (median of per-round ratios)  (rounds: "
        f"{[round(x, 2) for x in rates[1]]} / {[round(x, 2) for x in rates[8]]})"
    )
    print(f"requests per CPU-second  max_batch 1: {c1:.2f}  max_batch 8: {c8:.2f}  ratio {cpu_ratio:.2f}x (median of per-round ratios)")
    print(f"time to first answer (load + 1 request): median {statistics.median(firsts):.2f} s")
    print(f"memory: {before_load:.0f} MiB before loading, {after_load:.0f} MiB loaded, peak {peak_mib():.0f} MiB; identical answers: yes")
    print(f"load average {load}")
    model_note = f"tiny Qwen2-VL-style checkpoint, {args.layers} layer(s), hidden 32" if args.checkpoint is None else args.checkpoint
    comparison = (f"{model_note}; {args.requests - 1} requests of {args.frames} {size[0]}x{size[1]} images, {args.max_tokens} new tokens, "
                  "greedy, sent at once")
    figures = [
        {"name": "requests/s, max_batch 1", "value": round(r1, 3), "unit": "requests/s", "target": "", "comparison": comparison},
        {"name": "requests/s, max_batch 8", "value": round(r8, 3), "unit": "requests/s", "target": "", "comparison": comparison},
        {
            "name": "batching speed-up (max_batch 8 / 1), same answers",
            "value": round(ratio, 3),
            "unit": "x",
            "target": "> 1 with identical answers",
            "comparison": comparison + "; wall clock",
        },
        {"name": "requests per CPU-second, max_batch 1", "value": round(c1, 3), "unit": "requests/CPU-s", "target": "", "comparison": comparison},
        {"name": "requests per CPU-second, max_batch 8", "value": round(c8, 3), "unit": "requests/CPU-s", "target": "", "comparison": comparison},
        {
            "name": "batching speed-up in CPU time (max_batch 8 / 1), same answers",
            "value": round(cpu_ratio, 3),
            "unit": "x",
            "target": "> 1 with identical answers",
            "comparison": comparison,
        },
        {
            "name": "time to first answer (load + one request)",
            "value": round(statistics.median(firsts), 3),
            "unit": "s",
            "target": "",
            "comparison": model_note,
        },
        {
            "name": "resident memory with the model loaded",
            "value": round(after_load, 1),
            "unit": "MiB",
            "target": "",
            "comparison": f"{before_load:.0f} MiB before torch and transformers were imported",
        },
        {"name": "peak resident memory", "value": round(peak_mib(), 1), "unit": "MiB", "target": "", "comparison": "whole process, both settings"},
        {"name": "batches split after running out of memory", "value": splits, "unit": "count", "target": "0 on this size", "comparison": "all rounds"},
    ]
    record(args.out.stem, figures, "python benchmarks/bench_local.py " + " ".join(sys.argv[1:]), results_dir=args.out.parent)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
