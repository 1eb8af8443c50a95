"""The in-process ``transformers`` backend's memory against a plain ``model.generate`` script
at the same batch size (issue 44, item 4).

    python benchmarks/bench_local_memory.py [--rounds 3] [--requests 64] [--frames 30] [--batch 8] [--baseline f33d9c8]

A tiny Qwen2-VL-style checkpoint is built once (:mod:`povagent.testing.tiny_checkpoints`:
hidden size 32, 2 layers, random weights); ``--requests`` requests of ``--frames`` 512x512
frames each (the dataset's requests show 30) and a sentence, 16 new tokens, greedy. Three
contenders, each in a fresh process of its own (its peak RSS, ``VmHWM``, is its own), in an
order that alternates round by round (the machine is shared):

* ``script``: a plain script: ``AutoProcessor`` and ``AutoModelForImageTextToText``, the
  requests' messages through the processor's chat template in batches of ``--batch`` (padded
  on the left), ``model.generate`` on the main thread, decoded;
* ``backend``: today's ``TransformersBackend`` with ``max_batch`` = ``--batch``, every request
  sent at once (as the runner does);
* ``before``: the same backend from the ``povagent`` package of commit ``--baseline``.

The figure is the median over rounds of peak(backend) / peak(script), held to <= 1.2; the
answers of all three must be identical (else the script fails). CPU seconds (user + system)
of each process and the load average are printed beside. Writes
``benchmarks/results/bench_local_memory.json``.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import tempfile
from pathlib import Path
from typing import Any

from baseline_code import baseline_checkout, child_json, cpu_seconds, peak_rss_mib
from results_file import figure, record

SENTENCE = "Sentence: the mug {i} is left of the sofa. Output ONLY valid JSON, no other text."


def request_frames(i: int, n_frames: int) -> list[Any]:
    """Request ``i``'s ``n_frames`` distinct 512x512 RGB frames (made when it is asked, so
    neither contender holds every request's pictures at once)."""
    import numpy as np
    from PIL import Image

    yy, xx = np.mgrid[0:512, 0:512]
    return [
        Image.fromarray(np.stack([(xx * (k + 1) + 7 * i) % 256, (yy * (i % 5 + 1)) % 256, (xx + yy + 13 * k) % 256], axis=-1).astype(np.uint8))
        for k in range(n_frames)
    ]


def run_script(checkpoint: str, n_requests: int, n_frames: int, batch: int, max_tokens: int) -> list[str]:
    """The plain script: chat template, ``generate`` in batches, decode."""
    import torch
    from transformers import AutoModelForImageTextToText, AutoProcessor

    processor = AutoProcessor.from_pretrained(checkpoint, trust_remote_code=True)
    processor.tokenizer.padding_side = "left"
    model = AutoModelForImageTextToText.from_pretrained(checkpoint, trust_remote_code=True).eval()
    texts: list[str] = []
    for start in range(0, n_requests, batch):
        conversations = []
        for i in range(start, min(start + batch, n_requests)):
            content: list[dict[str, Any]] = []
            for k, picture in enumerate(request_frames(i, n_frames)):
                content += [{"type": "text", "text": f"Image {k}:"}, {"type": "image", "image": picture}]
            content.append({"type": "text", "text": SENTENCE.format(i=i)})
            conversations.append([{"role": "user", "content": content}])
        inputs = processor.apply_chat_template(conversations, tokenize=True, add_generation_prompt=True, return_dict=True,
                                               return_tensors="pt", padding=True)  # fmt: skip
        with torch.inference_mode():
            output = model.generate(**inputs, max_new_tokens=max_tokens, do_sample=False, temperature=None, top_p=None, top_k=None)
        texts += processor.tokenizer.batch_decode(output[:, inputs["input_ids"].shape[1]:], skip_special_tokens=True,
                                                  clean_up_tokenization_spaces=False)  # fmt: skip
    return texts


def run_backend(checkpoint: str, n_requests: int, n_frames: int, batch: int, max_tokens: int) -> list[str]:
    """The backend, every request sent at once (its queue batches them)."""
    from povagent.answers.spec import AnswerSpec, frame_answer_schema
    from povagent.exchange.images import ImageStore
    from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
    from povagent_plugins.backends.transformers_backend import TransformersBackend

    store = ImageStore()
    requests = []
    for i in range(n_requests):
        parts: list[Any] = []
        for k, picture in enumerate(request_frames(i, n_frames)):
            parts += [TextPart(f"Image {k}:"), ImagePart(store.add_pil(picture).image_hash)]
        parts.append(TextPart(SENTENCE.format(i=i)))
        spec = AnswerSpec(schema=frame_answer_schema(n_frames, 512, 512), n_frames=n_frames, asks_frame=True)
        requests.append(Request((Message("user", tuple(parts)),), spec, GenerationParams(max_tokens=max_tokens, temperature=0.0)))

    async def answer() -> list[str]:
        backend = TransformersBackend(model=checkpoint, trust_remote_code=True, max_batch=batch)
        try:
            await backend.start()
            return [r.text for r in await asyncio.gather(*(backend.complete(r, store) for r in requests))]
        finally:
            await backend.aclose()

    return asyncio.run(answer())


def measure(kind: str, args: argparse.Namespace, checkpoint: Path, pythonpath: Path | None) -> dict[str, Any]:
    argv = ["--child", kind, "--checkpoint", str(checkpoint), "--requests", str(args.requests), "--frames", str(args.frames)]
    return child_json(__file__, [*argv, "--batch", str(args.batch), "--max-tokens", str(args.max_tokens)], pythonpath)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--requests", type=int, default=64)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--batch", type=int, default=8)
    parser.add_argument("--max-tokens", type=int, default=16)
    parser.add_argument("--baseline", default="f33d9c8", help="the commit whose backend is measured as 'before'")
    parser.add_argument("--child", choices=("script", "backend"), help=argparse.SUPPRESS)
    parser.add_argument("--checkpoint", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        run = run_script if args.child == "script" else run_backend
        texts = run(str(args.checkpoint), args.requests, args.frames, args.batch, args.max_tokens)
        print(json.dumps({"peak_mib": peak_rss_mib(), "cpu_s": cpu_seconds(), "answers": texts}))
        return
    from povagent.testing.tiny_checkpoints import build_qwen2_vl

    with tempfile.TemporaryDirectory(prefix="bench_local_memory_") as tmp:
        checkpoint = build_qwen2_vl(Path(tmp) / "qwen2_vl", layers=2)
        old = baseline_checkout(args.baseline, Path(tmp) / "baseline")
        print(f"load before: {os.getloadavg()}")
        contenders = (("script", "script", None), ("backend", "backend", None), ("before", "backend", old))
        got: dict[str, list[dict[str, Any]]] = {name: [] for name, _, _ in contenders}
        for r in range(args.rounds):
            order = contenders if r % 2 == 0 else tuple(reversed(contenders))
            for name, kind, path in order:
                got[name].append(measure(kind, args, checkpoint, path))
            answers = {name: tuple(got[name][-1]["answers"]) for name in got}
            if len(set(answers.values())) != 1:
                raise SystemExit(f"round {r + 1}: the contenders answered differently")
            print(f"round {r + 1}: " + "; ".join(
                f"{name} {got[name][-1]['peak_mib']:.0f} MiB peak, {got[name][-1]['cpu_s']:.1f} s CPU" for name in got), flush=True)
    ratio = {name: statistics.median(m["peak_mib"] / s["peak_mib"] for m, s in zip(got[name], got["script"])) for name in ("backend", "before")}
    peak = {name: statistics.median(m["peak_mib"] for m in runs) for name, runs in got.items()}
    load = os.getloadavg()
    print(f"peak RSS over the plain script's: backend {ratio['backend']:.3f}x (goal <= 1.2), before {ratio['before']:.3f}x; "
          f"identical answers; load after: {load}")
    setting = (f"tiny Qwen2-VL-style checkpoint (2 layers, hidden 32); {args.requests} requests of {args.frames} 512x512 frames, "
               f"{args.max_tokens} new tokens, greedy; batch {args.batch}")  # fmt: skip
    record("bench_local_memory", [
        figure(f"peak RSS, backend at max_batch {args.batch} / plain script", round(ratio["backend"], 3), "x", target="<= 1.2",
               comparison=f"{setting}; before (commit {args.baseline}): {ratio['before']:.3f}x; median of {args.rounds} rounds, "
               "each contender in its own process; identical answers"),
        figure("peak RSS, plain script", round(peak["script"], 1), "MiB", comparison=setting),
        figure(f"peak RSS, backend at max_batch {args.batch}", round(peak["backend"], 1), "MiB",
               comparison=f"before (commit {args.baseline}): {peak['before']:.1f} MiB"),
    ])


if __name__ == "__main__":
    main()
