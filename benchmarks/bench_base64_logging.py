"""What litellm's base64 truncation for logging costs, what povagent saves, and what a callback sees.

    python benchmarks/bench_base64_logging.py [--requests 64] [--rounds 3] [--model hosted_vllm/bench-model]

litellm reads ``MAX_BASE64_LENGTH_FOR_LOGGING`` once, at import (``litellm/constants.py``,
default 64). After every successful call it copies the messages and replaces each data URL's
base64 longer than that by a size placeholder (``truncate_base64_in_messages_async``, a regex
pass over the whole payload, in a worker thread above 256 K characters); the copy becomes the
``messages`` of the standard logging payload that every litellm callback receives. ``0`` skips
the pass, and the payload then holds the messages as sent: whole images.

povagent skips the pass for its own calls while nothing can read the payload
(``povagent/engine/llm_logging.py``), and leaves it to litellm as soon as a callback is
registered. Three settings, each in its own child process (litellm must be imported afresh
for each), in rotating order, against one loopback server (a subprocess), 30 inline frames of
512x512 per request through ``LiteLLMBackend.complete``:

* ``litellm truncates``: ``MAX_BASE64_LENGTH_FOR_LOGGING=64`` exported (litellm's default
  value; a user's own setting is respected, so povagent skips nothing): the cost as before;
* ``povagent``: nothing exported, povagent's default;
* ``off (0)``: ``0`` exported, truncation off for everyone (the unsafe setting, for reference).

Each child reports its process CPU per request (client side only) and requests/s with no
callback registered, then registers a litellm callback and sends one more request: the longest
data URL that callback was handed in the standard logging payload (a few dozen characters when
truncated, ~250 K for a whole image). Prints per-round figures, the median CPU saving, and
what a callback sees.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from baseline_code import child_json

HERE = Path(__file__).resolve().parent


def child(args: argparse.Namespace) -> None:
    """One measurement in this process (litellm imported here, under the inherited setting)."""
    sys.path.insert(0, str(HERE))
    from bench_image_transport import the_request

    from povagent.engine.llm_import import import_litellm
    from povagent.exchange.images import ImageStore
    from povagent_plugins.backends.litellm_backend import LiteLLMBackend

    litellm = import_litellm()
    from litellm.integrations.custom_logger import CustomLogger

    longest = {"data_url": 0}

    class Watch(CustomLogger):
        """Measures the longest data URL a logging callback is handed."""

        async def async_log_success_event(self, kwargs, response_obj, start_time, end_time):
            payload = kwargs.get("standard_logging_object") or {}
            text = json.dumps(payload.get("messages"), default=str)
            start = 0
            while (i := text.find("data:image", start)) >= 0:
                end = text.find('"', i)
                longest["data_url"] = max(longest["data_url"], end - i)
                start = end

    frames = sorted((Path(args.workdir) / "povbench").glob("artifacts/*/exploration_images/*.png"))
    store = ImageStore()
    request = the_request(store, frames)
    os.environ.setdefault("BENCH_KEY", "bench-key")
    backend = LiteLLMBackend(model=args.model, api_base=args.url, api_key_env="BENCH_KEY", timeout=120)

    async def run() -> tuple[float, float]:
        await backend.start()
        for _ in range(2):
            await backend.complete(request, store)
        sem = asyncio.Semaphore(args.concurrency)

        async def one() -> None:
            async with sem:
                await backend.complete(request, store)

        cpu0, t0 = time.process_time(), time.perf_counter()
        await asyncio.gather(*(one() for _ in range(args.requests)))
        wall = time.perf_counter() - t0
        await asyncio.sleep(1.0)  # litellm's logging of the last calls finishes (and is counted)
        return wall, time.process_time() - cpu0

    wall, cpu = asyncio.run(run())
    # a second, short pass with a callback registered: what a callback would be handed
    litellm.callbacks = [Watch()]

    async def watched() -> None:
        await backend.complete(request, store)
        await asyncio.sleep(1.0)

    asyncio.run(watched())
    print(json.dumps({"rps": args.requests / wall, "cpu_ms": 1000 * cpu / args.requests,
                      "longest_logged_data_url": longest["data_url"]}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=64)
    ap.add_argument("--concurrency", type=int, default=16)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--model", default="hosted_vllm/bench-model")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--url", help=argparse.SUPPRESS)
    ap.add_argument("--workdir", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return

    sys.path.insert(0, str(HERE))
    from bench_image_transport import thirty_frames

    with tempfile.TemporaryDirectory(prefix="povagent-b64log-") as tmp:
        workdir = Path(tmp)
        thirty_frames(workdir / "povbench")
        # a plain server: this measures the client, whose work does not depend on what the server checks
        server = subprocess.Popen([sys.executable, "-m", "povagent.testing.loopback_server", "--lifetime", "1800"],
                                  stdout=subprocess.PIPE, text=True)
        url = server.stdout.readline().strip()  # type: ignore[union-attr]
        settings = {"litellm truncates": "64", "povagent": None, "off (0)": "0"}
        names = list(settings)
        results: dict[str, list[dict]] = {k: [] for k in settings}
        try:
            print(f"{args.requests} inline 30-frame requests per child, concurrency {args.concurrency}, model {args.model}")
            print(f"{'round':>5} {'setting':>17} {'req/s':>7} {'client CPU ms/req':>18} {'longest data URL a callback got':>32}")
            for r in range(args.rounds):
                for name in names[r % len(names):] + names[: r % len(names)]:
                    env = dict(os.environ)
                    env.pop("MAX_BASE64_LENGTH_FOR_LOGGING", None)
                    if settings[name] is not None:
                        env["MAX_BASE64_LENGTH_FOR_LOGGING"] = settings[name]
                    argv = ["--child", "--url", url, "--workdir", str(workdir), "--requests", str(args.requests)]
                    doc = child_json(__file__, [*argv, "--concurrency", str(args.concurrency), "--model", args.model], env=env)
                    results[name].append(doc)
                    print(f"{r:>5} {name:>17} {doc['rps']:>7.1f} {doc['cpu_ms']:>18.1f} {doc['longest_logged_data_url']:>32,}", flush=True)
        finally:
            server.terminate()
            server.wait(10)
    before = statistics.median(d["cpu_ms"] for d in results["litellm truncates"])
    print()
    for name in names:
        cpu = statistics.median(d["cpu_ms"] for d in results[name])
        longest = max(d["longest_logged_data_url"] for d in results[name])
        print(f"{name:>17}: median client CPU {cpu:6.1f} ms/request ({100 * (before - cpu) / before:+5.1f}% saved), "
              f"median {statistics.median(d['rps'] for d in results[name]):5.1f} requests/s; a registered callback got "
              f"data URLs of up to {longest:,} characters ({'whole images' if longest > 10_000 else 'truncated'})")
    # per round, povagent against litellm's truncation: the same round ran both on the same machine
    per_round = [1 - p["cpu_ms"] / t["cpu_ms"] for p, t in zip(results["povagent"], results["litellm truncates"])]
    print(f"povagent's saving of client CPU per request, median of per-round ratios: {100 * statistics.median(per_round):.1f}%")

if __name__ == "__main__":
    main()
