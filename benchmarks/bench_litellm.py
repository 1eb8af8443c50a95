"""Throughput of the litellm backend against a local server with instant answers, on generated frames.

Target: our code takes at most 10% of the time per request; the rest is litellm's own (its
request building, the OpenAI client, httpx, the event loop).

Each request is the ``basic`` strategy's kind: a house's frames of a dataset made by
``povagent generate`` (``--data``, or one house generated into a temporary folder), each after
its "Image i:" label, inline as base64 data URLs, then the sentence. The loopback server runs in
a subprocess (``python -m povagent.testing.loopback_server --expect-sha256``) so the measured
process holds only the client; it decodes every image and refuses (400) any that is not one of
the dataset's frames, and the script prints how many it checked. At concurrency 32 the script
measures, in ``--rounds`` rounds alternating the order of the two:

* requests/s and process CPU per request through ``LiteLLMBackend.complete`` and through bare
  ``litellm.acompletion`` with the same prebuilt messages (litellm alone, no povagent code);
  the ratio is taken within each round (the machine is shared) and the median reported;
* our code's time per request, measured exactly: the synchronous work in ``complete()``
  before litellm starts (messages with data URLs, generation parameters, key lookup) and after
  it returns (text, usage) has no await in it, so the event-loop thread's CPU time
  (``time.thread_time``) across it is our code's alone (wall clock would also count litellm's
  logging threads preempting it). ``litellm.completion_cost``, which we call to record cost,
  is reported apart;
* litellm's own CPU time per request: the process CPU time of the run divided by the requests,
  minus ours.

Usage::

    python benchmarks/bench_litellm.py [--data FOLDER] [--requests 320] [--concurrency 32] [--images 30] [--rounds 4]
"""

from __future__ import annotations

import argparse
import asyncio
import importlib.metadata
import os
import shutil
import statistics
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from generated_frames import frame_digests, generated_dataset, start_verifying_server, stop_verifying_server

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.engine.llm_import import import_litellm
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent_plugins.backends.litellm_backend import LiteLLMBackend
from povagent_plugins.backends.openai_messages import openai_messages


def make_request(store: ImageStore, frames: list[Path], sentence: str) -> Request:
    """A labelled multi-image request like the basic strategy's, over a generated house's frames."""
    parts: list = []
    for i, frame in enumerate(frames):
        parts += [TextPart(f"Image {i}:"), ImagePart(store.add_file(frame).image_hash)]
    parts.append(TextPart(f"Sentence: {sentence} Answer in JSON."))
    spec = AnswerSpec(schema=frame_answer_schema(len(frames), 512, 512), n_frames=len(frames))
    return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=GenerationParams(max_tokens=256))


def first_house(data: Path, n_images: int) -> tuple[list[Path], str]:
    """The frames (the first ``n_images``) and sentence of the data set's first Inferred instance."""
    from povagent.dataset.loader import load_dataset

    inst = next(i for i in load_dataset(data).instances() if i.condition.value == "a")
    return [f.file for f in inst.frames][:n_images], inst.sentence


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
    workdir = Path(tempfile.mkdtemp(prefix="bench-litellm-"))
    data = generated_dataset(args.data, workdir, houses=1)
    frames, sentence = first_house(data, args.images)
    frame_digests(data, workdir / "frames.sha256")
    proc, url = start_verifying_server(workdir / "frames.sha256", lifetime_s=3600)
    try:
        store = ImageStore()
        request = make_request(store, frames, sentence)
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

        # alternate the two over `rounds` rounds; ratios within a round (the machine is shared).
        # litellm finishes each request's logging in background tasks, which then slow down
        # whatever runs next: the loop settles before every run, and the order flips each
        # round so neither side always runs second.
        rounds: list[dict[str, tuple[float, float]]] = []
        ours_per_round: list[tuple[float, float]] = []
        pair = (("litellm alone", bare_litellm), ("povagent backend", through_backend))
        n = args.requests
        print(f"litellm {importlib.metadata.version('litellm')} | requests {n} per run | concurrency {args.concurrency} | "
              f"{len(frames)} generated frames per request from {data} "
              f"({sum(f.stat().st_size for f in frames) / len(frames) / 1024:.0f} KB PNG each, "
              f"~{len(str(messages)) / 1024 / 1024:.1f} MiB of data URLs)")
        print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
        print(f"{'round':>5} {'alone req/s':>12} {'CPU ms/req':>11} {'backend req/s':>14} {'CPU ms/req':>11} {'req/s ratio':>12}")
        for round_ in range(args.rounds):
            got: dict[str, tuple[float, float]] = {}
            for label, one in pair if round_ % 2 == 0 else pair[::-1]:
                await asyncio.sleep(args.settle)
                instrumented = one is through_backend
                if instrumented:
                    timings.ours.clear()
                    timings.cost.clear()
                    litellm.acompletion, litellm.completion_cost = timed_acompletion, timed_cost
                try:
                    got[label] = await drive(n, args.concurrency, one)
                finally:
                    litellm.acompletion, litellm.completion_cost = real_acompletion, real_cost
                if instrumented:
                    ours_per_round.append((sum(timings.ours) / n, sum(timings.cost) / n))
            rounds.append(got)
            (wl, cl), (wb, cb) = got["litellm alone"], got["povagent backend"]
            print(f"{round_:>5} {n / wl:>12.1f} {1000 * cl / n:>11.1f} {n / wb:>14.1f} {1000 * cb / n:>11.1f} {wl / wb:>11.2f}x",
                  flush=True)
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")

        med = {label: (statistics.median(r[label][0] for r in rounds), statistics.median(r[label][1] for r in rounds))
               for label, _ in pair}
        (wall_l, cpu_l), (wall_b, cpu_b) = med["litellm alone"], med["povagent backend"]
        ours = statistics.median(o for o, _ in ours_per_round)
        cost = statistics.median(c for _, c in ours_per_round)
        ours_excl_cost = ours - cost
        litellm_own = cpu_b / n - ours
        print()
        print(f"{'(medians)':24}{'req/s':>10}{'CPU ms/req':>12}")
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
        ratios = [r["litellm alone"][0] / r["povagent backend"][0] for r in rounds]
        print(f"throughput ratio backend / litellm alone (median of rounds): {statistics.median(ratios):.2f} "
              f"(rounds {', '.join(f'{x:.2f}' for x in ratios)})")
    finally:
        checked = stop_verifying_server(proc)
        print(f"server: {checked.get('requests')} requests, {checked.get('images_fetched')} images checked against the "
              f"dataset's SHA-256s, {checked.get('image_failures')} refused")
        shutil.rmtree(workdir, ignore_errors=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=320)
    ap.add_argument("--concurrency", type=int, default=32)
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate one house)")
    ap.add_argument("--images", type=int, default=30, help="frames per request (the house's first N)")
    ap.add_argument("--rounds", type=int, default=4, help="alternating rounds; medians and per-round ratios are reported")
    ap.add_argument("--settle", type=float, default=2.0, help="seconds the loop idles before each run (litellm's logging drains)")
    asyncio.run(main_async(ap.parse_args()))


if __name__ == "__main__":
    main()
