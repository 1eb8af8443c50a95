"""Throughput of the litellm backend against a local server with instant answers.

Target: our code takes at most 10% of the time per request; the rest is litellm's own (its
request building, the OpenAI client, httpx, the event loop).

The loopback server runs in a subprocess (``python -m povagent.testing.loopback_server``) so the
measured process holds only the client. At concurrency 32 the script measures:

* requests/s through ``LiteLLMBackend.complete`` and through bare ``litellm.acompletion``
  with the same prebuilt messages (litellm alone, no povagent code);
* our code's time per request, measured exactly: the synchronous work in ``complete()``
  before litellm starts (messages with data URLs, generation parameters, key lookup) and after
  it returns (text, usage) has no await in it, so the event-loop thread's CPU time
  (``time.thread_time``) across it is our code's alone (wall clock would also count litellm's
  logging threads preempting it). ``litellm.completion_cost``, which we call to record cost,
  is reported apart;
* litellm's own CPU time per request: the process CPU time of the run divided by the requests,
  minus ours.

Usage::

    python benchmarks/bench_litellm.py [--requests 320] [--concurrency 32] [--images 30] [--size 64] [--rounds 2]
"""

from __future__ import annotations

import argparse
import asyncio
import importlib.metadata
import os
import random
import subprocess
import sys
import time
from dataclasses import dataclass, field

from PIL import Image

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent.exchange.images import ImageStore
from povagent.engine.llm_import import import_litellm
from povagent_plugins.backends.litellm_backend import LiteLLMBackend
from povagent_plugins.backends.openai_messages import openai_messages


def make_request(store: ImageStore, n_images: int, size: int) -> Request:
    """A labelled multi-image request like the basic strategy's (noise images, so PNGs are real-sized)."""
    rng = random.Random(0)
    parts: list = []
    for i in range(n_images):
        im = Image.frombytes("RGB", (size, size), bytes(rng.getrandbits(8) for _ in range(size * size * 3)))
        h = store.add_pil(im).image_hash
        parts += [TextPart(f"Image {i}:"), ImagePart(h)]
    parts.append(TextPart("Sentence: the mug is to the left of the sofa. Answer in JSON."))
    spec = AnswerSpec(schema=frame_answer_schema(n_images, 512, 512), n_frames=n_images)
    return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=GenerationParams(max_tokens=256))


def start_server() -> tuple[subprocess.Popen, str]:
    """The loopback server in a subprocess; returns the process and its base URL."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--lifetime", "900"],
        stdout=subprocess.PIPE,
        text=True,
    )
    url = proc.stdout.readline().strip()  # type: ignore[union-attr]
    if not url.startswith("http://127.0.0.1:"):
        proc.kill()
        raise SystemExit(f"loopback server did not start (printed {url!r})")
    return proc, url


@dataclass
class Timings:
    """Per-request timing samples (seconds)."""

    ours: list[float] = field(default_factory=list)
    cost: list[float] = field(default_factory=list)


async def drive(n: int, concurrency: int, one) -> tuple[float, float]:
    """Run ``one()`` n times with ``concurrency`` in flight; (wall s, process CPU s)."""
    sem = asyncio.Semaphore(concurrency)

    async def task() -> None:
        async with sem:
            await one()

    cpu0, t0 = time.process_time(), time.perf_counter()
    await asyncio.gather(*[task() for _ in range(n)])
    return time.perf_counter() - t0, time.process_time() - cpu0


async def main_async(args: argparse.Namespace) -> None:
    litellm = import_litellm()
    proc, url = start_server()
    try:
        store = ImageStore()
        request = make_request(store, args.images, args.size)
        backend = LiteLLMBackend(model="openai/bench-model", api_base=url, api_key_env="BENCH_KEY", timeout=60)
        messages = openai_messages(request, store)
        os.environ.setdefault("BENCH_KEY", "bench-key")

        # -- instrument: litellm.acompletion entry/exit and completion_cost ----------------------
        timings = Timings()
        real_acompletion, real_cost = litellm.acompletion, litellm.completion_cost
        entered: dict[int, float] = {}
        exited: dict[int, float] = {}

        async def timed_acompletion(*a, **k):
            task = id(asyncio.current_task())
            entered[task] = time.thread_time()  # our pre-work is done
            try:
                return await real_acompletion(*a, **k)
            finally:
                exited[task] = time.thread_time()  # our post-work starts

        def timed_cost(*a, **k):
            t = time.thread_time()
            try:
                return real_cost(*a, **k)
            finally:
                timings.cost.append(time.thread_time() - t)

        async def through_backend() -> None:
            task = id(asyncio.current_task())
            t0 = time.thread_time()
            await backend.complete(request, store)
            t_end = time.thread_time()
            # neither span holds an await: the loop thread's CPU time across them is ours alone
            timings.ours.append((entered.pop(task) - t0) + (t_end - exited.pop(task)))

        async def bare_litellm() -> None:
            await real_acompletion(
                model="openai/bench-model", api_base=url, api_key="bench-key", messages=messages,
                max_tokens=256, timeout=60, num_retries=0, max_retries=0,
            )

        # warm up (client creation, first-call caches) outside the measurements
        for _ in range(3):
            await backend.complete(request, store)
            await bare_litellm()

        # alternate the two, best of `rounds`: the machine is shared, so noise only slows a run.
        # litellm finishes each request's logging in background tasks, which then slow down
        # whatever runs next: the loop settles before every run, and the order flips each
        # round so neither side always runs second.
        results: dict[str, tuple[float, float]] = {}
        pair = (("litellm alone", bare_litellm), ("povagent backend", through_backend))
        for round_ in range(args.rounds):
            for label, one in pair if round_ % 2 == 0 else pair[::-1]:
                await asyncio.sleep(args.settle)
                instrumented = one is through_backend
                if instrumented:
                    timings.ours.clear()
                    timings.cost.clear()
                    litellm.acompletion, litellm.completion_cost = timed_acompletion, timed_cost
                try:
                    wall, cpu = await drive(args.requests, args.concurrency, one)
                finally:
                    litellm.acompletion, litellm.completion_cost = real_acompletion, real_cost
                if label not in results or wall < results[label][0]:
                    results[label] = (wall, cpu)
                    if instrumented:
                        best = Timings(list(timings.ours), list(timings.cost))
        timings = best

        n = args.requests
        (wall_l, cpu_l), (wall_b, cpu_b) = results["litellm alone"], results["povagent backend"]
        ours = sum(timings.ours) / n
        cost = sum(timings.cost) / n
        ours_excl_cost = ours - cost
        litellm_own = cpu_b / n - ours
        body_kb = len(str(messages)) / 1024
        print(f"litellm {importlib.metadata.version('litellm')} | requests {n} | concurrency {args.concurrency} | "
              f"{args.images} images of {args.size}px per request (~{body_kb:.0f} KiB of data URLs)")
        print(f"{'':24}{'req/s':>10}{'CPU ms/req':>12}")
        print(f"{'litellm alone':24}{n / wall_l:>10.1f}{1000 * cpu_l / n:>12.2f}")
        print(f"{'povagent backend':24}{n / wall_b:>10.1f}{1000 * cpu_b / n:>12.2f}")
        print()
        print(f"our code per request:            {1000 * ours_excl_cost:8.3f} ms  (messages, params, key, text, usage)")
        print(f"completion_cost (called by us):  {1000 * cost:8.3f} ms  (0 when litellm priced the response itself)")
        print(f"litellm's own per request (CPU): {1000 * litellm_own:8.3f} ms")
        share = ours_excl_cost / (ours + litellm_own)
        share_with_cost = ours / (ours + litellm_own)
        print(f"our share of the time per request: {100 * share:.1f}% (with completion_cost: {100 * share_with_cost:.1f}%)"
              f"  target <= 10%: {'met' if share_with_cost <= 0.10 else 'NOT met'}")
        print(f"throughput ratio backend / litellm alone: {(n / wall_b) / (n / wall_l):.2f}")
    finally:
        proc.terminate()
        proc.wait(10)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=320)
    ap.add_argument("--concurrency", type=int, default=32)
    ap.add_argument("--images", type=int, default=30)
    ap.add_argument("--size", type=int, default=64, help="image side in pixels (noise PNG)")
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds; the fastest of each is reported")
    ap.add_argument("--settle", type=float, default=2.0, help="seconds the loop idles before each run (litellm's logging drains)")
    asyncio.run(main_async(ap.parse_args()))


if __name__ == "__main__":
    main()
