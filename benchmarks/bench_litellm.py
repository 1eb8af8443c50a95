"""The litellm backend's cost per request against litellm alone and against raw httpx sending the same bytes.

Targets (issue 28): our code at most 10% of the time per request (the rest is litellm's own);
marginal client CPU per inline request at most 1.3x that of raw httpx sending the same bytes;
peak memory within 10% of litellm alone's.

Each request is the ``basic`` strategy's kind: a house's frames of a dataset made by
``povagent generate`` (``--data``, or one house generated into a temporary folder), each after
its "Image i:" label, inline as base64 data URLs, then the sentence. The loopback server runs in
a subprocess (``python -m povagent.testing.loopback_server --expect-sha256 --count-bodies``) so
the measured process holds only the client; it decodes every image and refuses (400) any that
is not one of the dataset's frames, and counts every request body by its SHA-256. Contenders,
all on that server at ``--concurrency``:

* ``povagent``: ``LiteLLMBackend.complete`` (messages built from the image store, generation
  parameters, key lookup, litellm, text and usage);
* ``litellm alone``: bare ``litellm.acompletion`` with the same messages prebuilt;
* ``raw httpx``: an ``httpx.AsyncClient`` POSTing the body povagent sends, JSON-encoded anew for
  every request with the encoder that reproduces povagent's bytes exactly (the openai SDK's and
  httpx's ``json=``: compact, UTF-8; litellm's own handler for ``hosted_vllm/``: ``json.dumps``
  defaults), as any client must encode what it sends;
* ``raw httpx, bytes prebuilt``: the same bytes encoded once and POSTed as they are: the wire's
  own cost, a floor no JSON client reaches.

The body povagent sends is captured once (the first request's bytes, as handed to httpx); the
raw contenders send exactly those bytes, and the server's count of bodies by SHA-256 shows which
contenders' requests were byte-identical to it.

Marginal CPU per request is the slope of process CPU time between ``--small`` and
``--requests`` requests run back to back (fixed costs, such as opening connections, drop out).
Rounds rotate the contenders' order; ratios are taken within each round (the machine is shared)
and the median reported with the per-round values and the load average.

Our code's time per request is measured exactly: the synchronous work in ``complete()`` before
litellm starts (messages, generation parameters, key lookup) and after it returns (text, usage)
has no await in it, so the event-loop thread's CPU time (``time.thread_time``) across it is our
code's alone.

``--memory N`` (default 64; 0: none) then runs each contender in a fresh process of its own for
N requests after 3 warm-up requests, and reports its peak RSS (``VmHWM``) and its RSS before
the first request; ``litellm alone`` there takes its messages from the captured body (it imports
litellm only), the raw contenders import httpx only.

Usage::

    python benchmarks/bench_litellm.py [--data FOLDER] [--model openai/bench-model] [--requests 160] [--small 32]
                                       [--concurrency 32] [--rounds 4] [--memory 64]
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import importlib.metadata
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from baseline_code import child_json, peak_rss_mib
from generated_frames import frame_digests, generated_dataset, start_verifying_server, stop_verifying_server

#: The JSON encoders a client may use; the raw contender uses the one that gives povagent's bytes.
ENCODERS: dict[str, Callable[[Any], bytes]] = {
    "compact UTF-8 (openai SDK, httpx json=)": lambda body: json.dumps(
        body, ensure_ascii=False, separators=(",", ":"), allow_nan=False
    ).encode(),
    "json.dumps defaults (litellm's own handler)": lambda body: json.dumps(body).encode(),
}
CONTENDERS = ("raw httpx, bytes prebuilt", "raw httpx", "litellm alone", "povagent")


def make_request(store, frames: list[Path], sentence: str):
    """A labelled multi-image request like the basic strategy's, over a generated house's frames."""
    from povagent.answers.spec import AnswerSpec, frame_answer_schema
    from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart

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


def encoder_of(body: bytes) -> str:
    """The name of the encoder that reproduces ``body`` from its own JSON exactly."""
    payload = json.loads(body)
    for name, encode in ENCODERS.items():
        if encode(payload) == body:
            return name
    raise SystemExit("no known JSON encoder reproduces the body povagent sent: the raw contender cannot send the same bytes")


@dataclass
class Timings:
    """Per-request timing samples (seconds)."""

    ours: list[float] = field(default_factory=list)


async def drive(n: int, concurrency: int, one: Callable[[], Awaitable[None]]) -> tuple[float, float]:
    """Run ``one()`` n times with ``concurrency`` in flight; (wall s, process CPU s)."""
    sem = asyncio.Semaphore(concurrency)

    async def task() -> None:
        async with sem:
            await one()

    cpu0, t0 = time.process_time(), time.perf_counter()
    await asyncio.gather(*[task() for _ in range(n)])
    return time.perf_counter() - t0, time.process_time() - cpu0


class Contenders:
    """The four ways of sending the request, set up once in this process."""

    def __init__(self, litellm: Any, data: Path, url: str, model: str, images: int) -> None:
        import httpx

        from povagent.exchange.images import ImageStore
        from povagent_plugins.backends.litellm_backend import LiteLLMBackend
        from povagent_plugins.backends.openai_messages import openai_messages

        os.environ.setdefault("BENCH_KEY", "bench-key")
        self.litellm, self.url, self.model = litellm, url, model
        self.frames, sentence = first_house(data, images)
        self.store = ImageStore()
        self.request = make_request(self.store, self.frames, sentence)
        self.backend = LiteLLMBackend(model=model, api_base=url, api_key_env="BENCH_KEY", timeout=60)
        self.messages = openai_messages(self.request, self.store)
        self.real_acompletion = litellm.acompletion
        self.client = httpx.AsyncClient(timeout=60)
        self.body = b""
        self.encoder = ""
        self.payload: Any = None
        self.timings = Timings()
        self._entered: dict[int, float] = {}
        self._exited: dict[int, float] = {}

    async def capture(self) -> None:
        """One request through povagent, its body's bytes kept as httpx was handed them."""
        import httpx

        real_send = httpx.AsyncClient.send
        seen: list[httpx.Request] = []

        async def send(client, request, **kw):
            seen.append(request)
            return await real_send(client, request, **kw)

        httpx.AsyncClient.send = send  # type: ignore[method-assign]
        try:
            await self.backend.complete(self.request, self.store)
        finally:
            httpx.AsyncClient.send = real_send  # type: ignore[method-assign]
        posts = [r for r in seen if r.url.path.endswith("/chat/completions")]
        assert len(posts) == 1, f"{len(posts)} chat requests seen for one call"
        self.body = posts[0].content
        self.encoder = encoder_of(self.body)
        self.payload = json.loads(self.body)
        self.post_url = str(posts[0].url)

    # -- the contenders -----------------------------------------------------------------------
    async def raw_prebuilt(self) -> None:
        r = await self.client.post(self.post_url, content=self.body, headers=_HEADERS)
        r.raise_for_status()
        r.json()

    async def raw(self) -> None:
        r = await self.client.post(self.post_url, content=ENCODERS[self.encoder](self.payload), headers=_HEADERS)
        r.raise_for_status()
        r.json()

    async def litellm_alone(self) -> None:
        await self.real_acompletion(
            model=self.model, api_base=self.url, api_key="bench-key", messages=self.messages,
            max_tokens=256, timeout=60, num_retries=0, max_retries=0,
        )  # fmt: skip

    async def povagent(self) -> None:
        task = id(asyncio.current_task())
        t0 = time.thread_time()
        await self.backend.complete(self.request, self.store)
        t_end = time.thread_time()
        entered, exited = self._entered.pop(task, None), self._exited.pop(task, None)
        if entered is not None and exited is not None:  # instrumented (not a warm-up)
            # neither span holds an await: the loop thread's CPU time across them is ours alone
            self.timings.ours.append((entered - t0) + (t_end - exited))

    async def _timed_acompletion(self, *a, **k):
        task = id(asyncio.current_task())
        self._entered[task] = time.thread_time()  # our pre-work is done
        try:
            return await self.real_acompletion(*a, **k)
        finally:
            self._exited[task] = time.thread_time()  # our post-work starts

    def by_name(self) -> dict[str, Callable[[], Awaitable[None]]]:
        return dict(zip(CONTENDERS, (self.raw_prebuilt, self.raw, self.litellm_alone, self.povagent)))

    def instrument(self, on: bool) -> None:
        self.litellm.acompletion = self._timed_acompletion if on else self.real_acompletion


_HEADERS = {"Content-Type": "application/json", "Authorization": "Bearer bench-key"}


async def measure(args: argparse.Namespace, data: Path, url: str, workdir: Path) -> dict[str, Any]:
    from povagent.engine.llm_import import import_litellm

    litellm = import_litellm()
    c = Contenders(litellm, data, url, args.model, args.images)
    await c.capture()
    (workdir / "body.json").write_bytes(c.body)
    ones = c.by_name()
    # warm up (client creation, connections, first-call caches) outside the measurements
    for _ in range(3):
        for one in ones.values():
            await one()
    c.timings.ours.clear()
    sent = {name: 3 for name in CONTENDERS}  # the warm-ups
    sent["povagent"] += 1  # and the captured request

    small, large = args.small, args.requests
    print(f"litellm {importlib.metadata.version('litellm')} | {args.model} | {len(c.frames)} generated frames per request "
          f"from {data} ({sum(f.stat().st_size for f in c.frames) / len(c.frames) / 1024:.0f} KB PNG each) | "
          f"body {len(c.body) / 1e6:.2f} MB, sha256 {hashlib.sha256(c.body).hexdigest()[:16]}, encoder: {c.encoder}")
    print(f"concurrency {args.concurrency} | {small} and {large} requests per contender per round | {args.rounds} rounds")
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
    rounds: list[dict[str, dict[str, float]]] = []
    ours: list[float] = []
    print(f"{'round':>5}  " + "  ".join(f"{n:>26}" for n in CONTENDERS) + "   (marginal CPU ms/request | req/s)")
    for r in range(args.rounds):
        order = list(CONTENDERS[r % 4:] + CONTENDERS[: r % 4])
        got: dict[str, dict[str, float]] = {}
        for name in order:
            c.instrument(name == "povagent")
            try:
                runs = {}
                for n in (small, large):
                    await asyncio.sleep(args.settle)  # litellm's background logging of the last run drains
                    c.timings.ours.clear()
                    runs[n] = await drive(n, args.concurrency, ones[name])
                    sent[name] += n
            finally:
                c.instrument(False)
            if name == "povagent":
                ours.append(sum(c.timings.ours) / large)
            (_, cpu_s), (wall_l, cpu_l) = runs[small], runs[large]
            got[name] = {"marginal_ms": 1000 * (cpu_l - cpu_s) / (large - small), "cpu_ms": 1000 * cpu_l / large,
                         "rps": large / wall_l}  # fmt: skip
        rounds.append(got)
        print(f"{r:>5}  " + "  ".join(f"{got[n]['marginal_ms']:>15.1f} | {got[n]['rps']:>6.1f}" for n in CONTENDERS), flush=True)
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    await c.client.aclose()
    return {"rounds": rounds, "ours": ours, "sent": sent, "body_sha256": hashlib.sha256(c.body).hexdigest(),
            "body_bytes": len(c.body)}  # fmt: skip


def report(figures: dict[str, Any]) -> None:
    rounds = figures["rounds"]
    print()
    print("| contender | marginal client CPU ms/request (median) | CPU ms/request at the larger count | requests/s |")
    print("|---|---|---|---|")
    for name in CONTENDERS:
        med = {k: statistics.median(r[name][k] for r in rounds) for k in ("marginal_ms", "cpu_ms", "rps")}
        print(f"| {name} | {med['marginal_ms']:.1f} | {med['cpu_ms']:.1f} | {med['rps']:.1f} |")

    def ratio(a: str, b: str, key: str = "marginal_ms") -> tuple[float, list[float]]:
        per = [r[a][key] / r[b][key] for r in rounds]
        return statistics.median(per), per

    print()
    for other, goal in (("raw httpx", 1.3), ("raw httpx, bytes prebuilt", None), ("litellm alone", None)):
        med, per = ratio("povagent", other)
        verdict = f"  goal <= {goal}x: {'met' if med <= goal else 'NOT met'}" if goal else ""
        print(f"povagent / {other}, marginal CPU per request: {med:.2f}x (rounds {', '.join(f'{x:.2f}' for x in per)}){verdict}")
    med, per = ratio("povagent", "litellm alone", "rps")
    print(f"povagent / litellm alone, requests/s: {med:.2f}x (rounds {', '.join(f'{x:.2f}' for x in per)})")
    ours = statistics.median(figures["ours"])
    mine = statistics.median(r["povagent"]["cpu_ms"] for r in rounds)
    print(f"our code per request: {1000 * ours:.2f} ms of {mine:.1f} ms ({100 * ours * 1000 / mine:.1f}%; goal <= 10%)")


# -- memory: each contender in a fresh process ----------------------------------------------------
def child(args: argparse.Namespace) -> None:
    """One contender alone in this process: 3 warm-up requests, then ``--n``; its RSS figures."""
    name, url, body = args.child, args.url, Path(args.body).read_bytes()
    if name.startswith("raw"):
        import httpx

        client = httpx.AsyncClient(timeout=60)
        encode = ENCODERS[encoder_of(body)]
        payload = json.loads(body)
        post_url = url.rstrip("/") + "/chat/completions"

        async def one() -> None:
            content = body if name == "raw httpx, bytes prebuilt" else encode(payload)
            (await client.post(post_url, content=content, headers=_HEADERS)).raise_for_status()
    elif name == "litellm alone":
        import litellm

        messages = json.loads(body)["messages"]

        async def one() -> None:
            await litellm.acompletion(model=args.model, api_base=url, api_key="bench-key", messages=messages,
                                      max_tokens=256, timeout=60, num_retries=0, max_retries=0)  # fmt: skip
    else:
        from povagent.engine.llm_import import import_litellm

        import_litellm()
        c = Contenders(sys.modules["litellm"], Path(args.child_data), url, args.model, args.images)

        async def one() -> None:
            await c.backend.complete(c.request, c.store)

    async def run() -> dict[str, float]:
        for _ in range(3):
            await one()
        before = _rss_mb()
        await drive(args.n, args.concurrency, one)
        return {"rss_before_mb": before, "peak_rss_mb": peak_rss_mib()}

    print(json.dumps(asyncio.run(run())))


def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def memory(args: argparse.Namespace, data: Path, url: str, workdir: Path) -> dict[str, int]:
    """Peak RSS of each contender in its own process, two rounds in alternating order."""
    got: dict[str, list[dict[str, float]]] = {n: [] for n in CONTENDERS}
    for r in range(2):
        for name in CONTENDERS if r == 0 else CONTENDERS[::-1]:
            argv = ["--child", name, "--url", url, "--body", str(workdir / "body.json"), "--child-data", str(data), "--n", str(args.memory)]
            argv += ["--concurrency", str(args.concurrency), "--model", args.model, "--images", str(args.images)]
            got[name].append(child_json(__file__, argv))
    print()
    print(f"| contender, own process, {args.memory} requests at concurrency {args.concurrency} | RSS before the first timed "
          f"request (MB) | peak RSS (MB) |")
    print("|---|---|---|")
    for name in CONTENDERS:
        print(f"| {name} | {statistics.median(x['rss_before_mb'] for x in got[name]):.0f} | "
              f"{statistics.median(x['peak_rss_mb'] for x in got[name]):.0f} "
              f"(runs {', '.join(str(round(x['peak_rss_mb'])) for x in got[name])}) |")
    peak = {n: statistics.median(x["peak_rss_mb"] for x in got[n]) for n in CONTENDERS}
    ratio = peak["povagent"] / peak["litellm alone"]
    print(f"povagent / litellm alone, peak RSS: {ratio:.2f}x  goal <= 1.10x: {'met' if ratio <= 1.10 else 'NOT met'}")
    return {n: 2 * (3 + args.memory) for n in CONTENDERS}


async def main_async(args: argparse.Namespace) -> None:
    workdir = Path(tempfile.mkdtemp(prefix="bench-litellm-"))
    data = generated_dataset(args.data, workdir, houses=1)
    frame_digests(data, workdir / "frames.sha256")
    proc, url = start_verifying_server(workdir / "frames.sha256", lifetime_s=7200, count_bodies=True)
    mem_sent: dict[str, int] = {}
    figures: dict[str, Any] = {}
    try:
        figures = await measure(args, data, url, workdir)
        report(figures)
        if args.memory:
            mem_sent = memory(args, data, url, workdir)
    finally:
        checked = stop_verifying_server(proc)
        shutil.rmtree(workdir, ignore_errors=True)
    print()
    print(f"server: {checked.get('requests')} requests, {checked.get('images_fetched')} images checked against the "
          f"dataset's SHA-256s, {checked.get('image_failures')} refused")
    bodies = checked.get("body_sha256", {})
    if figures:
        sent = figures["sent"]
        same = bodies.get(figures["body_sha256"], 0)
        total = sum(sent.values()) + sum(mem_sent.values())
        print(f"request bodies byte-identical to povagent's ({figures['body_bytes']:,} bytes, sha256 "
              f"{figures['body_sha256'][:16]}...): {same} of {sum(bodies.values())} received; "
              f"sent by the contenders: {total} ({', '.join(f'{n} {sent[n] + mem_sent.get(n, 0)}' for n in CONTENDERS)})")
        others = {d[:16]: k for d, k in bodies.items() if d != figures["body_sha256"]}
        if others:
            print(f"other bodies (sha256 prefix: count): {others}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=160, help="requests of the larger run of each contender per round")
    ap.add_argument("--small", type=int, default=32, help="requests of the smaller run (the slope's other end)")
    ap.add_argument("--concurrency", type=int, default=32)
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate one house)")
    ap.add_argument("--model", default="openai/bench-model", help="litellm model string (openai/... or hosted_vllm/...)")
    ap.add_argument("--images", type=int, default=30, help="frames per request (the house's first N)")
    ap.add_argument("--rounds", type=int, default=4, help="rounds, contenders' order rotating; per-round ratios reported")
    ap.add_argument("--settle", type=float, default=2.0, help="seconds the loop idles before each run (litellm's logging drains)")
    ap.add_argument("--memory", type=int, default=64, help="requests per contender in the memory runs (0: none)")
    ap.add_argument("--child", choices=CONTENDERS, help=argparse.SUPPRESS)
    ap.add_argument("--url", help=argparse.SUPPRESS)
    ap.add_argument("--body", help=argparse.SUPPRESS)
    ap.add_argument("--child-data", dest="child_data", help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")  # both contenders: no cost-map download
    if args.child:
        child(args)
        return
    asyncio.run(main_async(args))


if __name__ == "__main__":
    main()
