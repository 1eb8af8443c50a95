"""Frames by reference: ``file`` vs ``inline``, and ``inline`` vs litellm alone, on one loopback server.

    python benchmarks/bench_image_transport.py [--data FOLDER] [--requests 128] [--concurrency 32] [--rounds 3]
                                               [--http] [--model hosted_vllm/bench-model]

The frames are the release's own kind: the 30 frames of the first Inferred instance of a
dataset made by ``povagent generate`` (``--data``, or one house generated into a temporary
folder; 512x512 rendered PNGs, ~200 KB each, ~8 MB of JSON per request inline). The loopback
server runs in a subprocess (``python -m povagent.testing.loopback_server``), with
``--fetch-images``: it decodes every data URL, opens every ``file://`` URL (beneath the folder
holding the dataset and the temporary folder, as vLLM's ``--allowed-local-media-path``),
computes each image's SHA-256 and answers 400 to a request holding any image whose digest is
not one of the dataset's frames. Every image is therefore verified at the server, whatever the
transport; the server's own counters are printed at the end.

Modes, each sending the same 30-frame request ``--requests`` times with ``--concurrency`` in
flight:

* ``litellm alone``: bare ``litellm.acompletion`` with the messages prebuilt (inline);
* ``inline``: ``LiteLLMBackend.complete`` (our message building, key lookup, usage, cost);
* ``file``: the same backend with ``images: {transport: file}``;
* ``http`` (with ``--http``): the same with the static server in this process.

Modes alternate in a rotating order for ``--rounds`` rounds; each round's requests/s and the
ratios within that round are printed, then their medians against the goals (inline/litellm
alone >= 1.0x, file/inline >= 5x). CPU per request (client, and the server's from /proc) is
printed too: on a machine shared with other work, requests/s measure the share of the CPU the
scheduler gave each side as much as the work, while CPU per request measures the work alone.
"""

from __future__ import annotations

import argparse
import asyncio
import importlib.metadata
import json
import os
import statistics
import tempfile
import time
from pathlib import Path

from generated_frames import frame_digests, generated_dataset, start_verifying_server, stop_verifying_server

from povagent.answers.spec import AnswerSpec, frame_answer_schema
from povagent.engine.llm_import import import_litellm
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent.exchange.transport import make_transport
from povagent_plugins.backends.litellm_backend import LiteLLMBackend
from povagent_plugins.backends.openai_messages import openai_messages

N_FRAMES = 30


def thirty_frames(data: Path) -> tuple[list[Path], str]:
    """The frames and sentence of the dataset's first Inferred instance (a house's 30 frames)."""
    from povagent.dataset.loader import load_dataset

    inst = next(i for i in load_dataset(data).instances() if i.condition.value == "a")
    frames = [f.file for f in inst.frames]
    assert len(frames) == N_FRAMES, f"{len(frames)} frames: generate houses with --frames {N_FRAMES}"
    return frames, inst.sentence


def the_request(store: ImageStore, frames: list[Path], sentence: str) -> Request:
    parts: list = []
    for i, path in enumerate(frames):
        parts += [TextPart(f"Image {i}:"), ImagePart(store.add_file(path).image_hash)]
    parts.append(TextPart(f"Sentence: {sentence} Answer in JSON."))
    spec = AnswerSpec(schema=frame_answer_schema(N_FRAMES, 512, 512), n_frames=N_FRAMES, asks_frame=True)
    return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=GenerationParams(max_tokens=64))


def process_cpu_s(pid: int) -> float:
    """User + system CPU seconds of a process so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


async def drive(n: int, concurrency: int, one) -> float:
    """Run ``one()`` n times with ``concurrency`` in flight; wall seconds."""
    sem = asyncio.Semaphore(concurrency)

    async def task() -> None:
        async with sem:
            await one()

    t0 = time.perf_counter()
    await asyncio.gather(*[task() for _ in range(n)])
    return time.perf_counter() - t0


async def main_async(args: argparse.Namespace, workdir: Path) -> None:
    litellm = import_litellm()
    data = generated_dataset(args.data, workdir, houses=1).resolve()
    frames, sentence = thirty_frames(data)
    digests = workdir / "expected.sha256"
    frame_digests(data, digests)
    os.environ.setdefault("BENCH_KEY", "bench-key")
    print(f"dataset {data}: {N_FRAMES} generated frames per request, {sum(f.stat().st_size for f in frames) / N_FRAMES / 1024:.0f} "
          f"KB each | load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
    proc, url = start_verifying_server(digests, extra=("--fetch-images", "--local-media-root", os.path.commonpath([data, workdir.resolve()])))
    sent_images = 0
    try:
        store = ImageStore()
        request = the_request(store, frames, sentence)
        backend = LiteLLMBackend(model=args.model, api_base=url, api_key_env="BENCH_KEY", timeout=120)
        inline_messages = openai_messages(request, store)
        body_mb = len(json.dumps(inline_messages)) / 1e6
        transports = {name: make_transport(name, dataset_root=data, cache_dir=workdir / "cache")
                      for name in (["file", "http"] if args.http else ["file"])}

        async def litellm_alone() -> None:
            await litellm.acompletion(
                model=args.model, api_base=url, api_key="bench-key", messages=inline_messages,
                max_tokens=64, timeout=120, num_retries=0, max_retries=0,
            )  # fmt: skip

        async def through_backend() -> None:
            await backend.complete(request, store)

        modes = {"litellm alone": (litellm_alone, None), "inline": (through_backend, None)}
        for name, transport in transports.items():
            modes[name] = (through_backend, transport)

        # warm up: client creation, the store's data URLs, first-call caches
        for one, transport in modes.values():
            with _attached(store, transport):
                await one()
            sent_images += N_FRAMES

        print(f"litellm {importlib.metadata.version('litellm')} | {args.model} | {N_FRAMES} frames of 512x512 per request "
              f"({body_mb:.1f} MB of JSON inline) | {args.requests} requests | concurrency {args.concurrency} | "
              f"{args.rounds} rounds")
        names = list(modes)
        rates: dict[str, list[float]] = {n: [] for n in names}
        # CPU per request, client (this process) and server: unlike requests/s, it does not depend
        # on how much of the shared machine the other processes take meanwhile
        cpu: dict[str, list[tuple[float, float]]] = {n: [] for n in names}
        header = "".join(f"{n:>15}" for n in names)
        print(f"{'round':>5}{header}   (requests/s)   inline/litellm  file/inline")
        for r in range(args.rounds):
            order = names[r % len(names):] + names[: r % len(names)]
            for name in order:
                one, transport = modes[name]
                await asyncio.sleep(args.settle)  # litellm's background logging of the last run drains
                c0, s0 = time.process_time(), process_cpu_s(proc.pid)
                with _attached(store, transport):
                    wall = await drive(args.requests, args.concurrency, one)
                    await asyncio.sleep(args.settle)  # litellm's logging of these requests is theirs
                c1, s1 = time.process_time(), process_cpu_s(proc.pid)
                sent_images += args.requests * N_FRAMES
                rates[name].append(args.requests / wall)
                cpu[name].append((1000 * (c1 - c0) / args.requests, 1000 * (s1 - s0) / args.requests))
            row = "".join(f"{rates[n][-1]:>15.1f}" for n in names)
            print(f"{r:>5}{row}   {'':>12}   {rates['inline'][-1] / rates['litellm alone'][-1]:>12.2f}x"
                  f"  {rates['file'][-1] / rates['inline'][-1]:>9.1f}x")
        for transport in transports.values():
            transport.close()
        await backend.aclose()
    finally:
        stats = stop_verifying_server(proc)

    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print()
    med = {n: statistics.median(v) for n, v in rates.items()}
    for n in names:
        client = statistics.median(c for c, _ in cpu[n])
        server_ms = statistics.median(s for _, s in cpu[n])
        print(f"median {n:>14}: {med[n]:7.1f} requests/s | CPU per request: client {client:6.1f} ms, "
              f"server {server_ms:6.1f} ms, both {client + server_ms:6.1f} ms")
    both = {n: statistics.median(c + s for c, s in cpu[n]) for n in names}
    print(f"CPU per request, inline / file (client + server): {both['inline'] / both['file']:.1f}x; "
          f"litellm alone / inline (client only): "
          f"{statistics.median(c for c, _ in cpu['litellm alone']) / statistics.median(c for c, _ in cpu['inline']):.2f}x")
    ratio_inline = statistics.median(i / a for i, a in zip(rates["inline"], rates["litellm alone"]))
    ratio_file = statistics.median(f / i for f, i in zip(rates["file"], rates["inline"]))
    print(f"inline / litellm alone (median of per-round ratios): {ratio_inline:.2f}x  goal >= 1.0x: "
          f"{'met' if ratio_inline >= 1.0 else 'NOT met'}")
    print(f"file / inline (median of per-round ratios): {ratio_file:.1f}x  goal >= 5x: {'met' if ratio_file >= 5 else 'NOT met'}")
    if "http" in rates:
        ratio_http = statistics.median(h / i for h, i in zip(rates["http"], rates["inline"]))
        print(f"http / inline (median of per-round ratios): {ratio_http:.1f}x (no goal: the images still cross a socket)")
    verified = stats.get("images_fetched")
    print(f"server: {stats.get('requests')} requests answered, {verified} images fetched and sha256-verified "
          f"(of {sent_images} sent), {stats.get('image_failures')} refused: "
          f"{'every image verified' if verified == sent_images and stats.get('image_failures') == 0 else 'NOT all verified'}")


class _attached:
    """``image_transport`` without closing the transport at the end (it is reused every round)."""

    def __init__(self, store: ImageStore, transport) -> None:
        self.store, self.transport = store, transport

    def __enter__(self) -> None:
        self.store.transport = self.transport

    def __exit__(self, *exc: object) -> None:
        self.store.transport = None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate one house)")
    ap.add_argument("--requests", type=int, default=128)
    ap.add_argument("--concurrency", type=int, default=32)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--settle", type=float, default=2.0, help="seconds idle before each run")
    ap.add_argument("--http", action="store_true", help="also measure the http transport")
    ap.add_argument("--model", default="hosted_vllm/bench-model",
                    help="litellm model string (hosted_vllm/: litellm's own HTTP client, as for a vLLM server; "
                         "openai/: the openai SDK, whose per-part request transform costs ~15 ms per 61-part request)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="povagent-transport-") as tmp:
        asyncio.run(main_async(args, Path(tmp)))


if __name__ == "__main__":
    main()
