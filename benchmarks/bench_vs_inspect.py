"""povagent's whole run (``inline``) against inspect_ai on one loopback server: requests/s and peak memory.

    python benchmarks/bench_vs_inspect.py --inspect-python /path/to/inspect-venv/bin/python
                                          [--data FOLDER | --houses 7] [--requests 256] [--rounds 4]
                                          [--concurrency 32] [--memory 64,1024] [--model hosted_vllm/bench-model]

inspect_ai is not a povagent dependency, and cannot share its environment: inspect_ai 0.3.285's
provider for OpenAI-compatible servers needs openai >= 3.4, litellm 1.103.7 needs openai < 3.
So inspect_ai runs under its own interpreter (``--inspect-python``: a virtual environment with
only ``pip install inspect-ai==0.3.285 openai==3.54.0``); this script, the server and povagent
run under the project's.

The frames are the release's own kind: a dataset made by ``povagent generate`` (``--data``, or
``--houses`` houses of 30 frames generated into a temporary folder: 512x512 rendered PNGs,
~40 Inferred/Stated instances per house). Each request carries its house's 30 frames inline
(base64, ~7.5 MB of JSON), each after its "Image i:" label, then the sentence. The loopback
OpenAI-compatible server runs in its own process and answers at once; it decodes every image
of every request and refuses (400, which fails the run) any whose SHA-256 is not a frame of the
dataset (``--expect-sha256``), and reports how many it checked. Each measurement runs in a
fresh child process, so its peak RSS (``VmHWM``) is its own, and is timed from the run's
start to its end (the tools' libraries, litellm and openai, imported before the clock starts):

* ``povagent``: the whole engine, as a user runs it: ``PipelineRun`` over the first N
  instances (the ``basic`` strategy, ``json`` parser, ``official`` scorer, response cache,
  rows journal, log), backend ``litellm`` with ``--model`` at the server's ``api_base``;
* ``inspect_ai``: ``inspect_ai.eval`` of a task whose N samples are the same instances' frames
  (``ContentImage`` with the PNG's path, as an inspect user writes it) and sentence (listed
  for it in a JSON file, as the child imports nothing of povagent; with ``--inspect-images
  data-url`` each frame is handed over as a ready data URL instead, built once per file, so
  inspect_ai neither reads nor encodes any image), solver
  ``generate()``, no scorer, model ``openai-api/loopback/bench-model`` (inspect's provider for
  an OpenAI-compatible server), ``max_connections`` = the concurrency; its eval log is written
  as usual.

Two settings give two different ratios, and both are published (``benchmarks/RESULTS.md``):
inspect_ai as it comes (its eval log embeds every image: over a gigabyte per 256 samples) with
povagent on ``hosted_vllm/`` (the defaults here), and ``--inspect-no-log-images --model
openai/bench-model``, both tools then on the openai SDK and inspect_ai writing no images. The
second is the like-for-like one; povagent's lead is smaller there but remains.

Throughput: ``--rounds`` rounds of ``--requests`` requests each, the two tools in alternating
order; the ratio is taken within each round (the machine is shared: rounds differ by what else
runs) and the median reported, with each tool's client CPU per request (the child's user+system
time over the run: the figure least moved by other load) and the load average. Memory: one run
of each tool at every size in ``--memory`` (empty: none).
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

from baseline_code import cpu_seconds, peak_rss_mib

FRAMES = 30  # per request: a generated house's exploration frames


def _instances(data: Path, n: int) -> list:
    """The first ``n`` Inferred/Stated instances, in the order povagent's run takes them."""
    from povagent.dataset.loader import load_dataset

    chosen = [i for i in load_dataset(data).instances() if i.condition.value in ("a", "b")][:n]
    assert len(chosen) == n, f"the data set has {len(chosen)} Inferred/Stated instances, {n} wanted: generate more --houses"
    return chosen


def run_povagent(data: Path, out: Path, url: str, n: int, concurrency: int, model: str) -> dict:
    """One povagent run over the first ``n`` Inferred/Stated instances; its figures."""
    from povagent.config.models import PipelineConfig
    from povagent.config.plugin_checks import resolve_components
    from povagent.dataset.loader import load_dataset
    from povagent.exchange.images import ImageStore
    from povagent.plugins import get_plugin_host
    from povagent.run.runner import PipelineRun

    os.environ.setdefault("BENCH_KEY", "bench-key")
    host = get_plugin_host()
    config = resolve_components(
        PipelineConfig.model_validate({
            "dataset": {"path": str(data)},
            "instances": {"conditions": ["a", "b"], "limit": n},
            "backend": {"name": "litellm", "options": {"model": model, "api_base": url, "api_key_env": "BENCH_KEY", "timeout": 300}},
            "strategy": "basic",
            "parser": "json",
            "scorers": ["official"],
            "concurrency": concurrency,
            "output": str(out),
        }),
        host,
    )  # fmt: skip
    dataset = load_dataset(data)
    run = PipelineRun(config, host=host, dataset=dataset, images=ImageStore())
    # litellm imported before the clock starts, as inspect_ai's own modules are: the run's
    # figures are the run's, not a one-off import's
    from povagent.engine.llm_import import import_litellm

    import_litellm()
    cpu0, t0 = cpu_seconds(), time.perf_counter()
    result = asyncio.run(run.run())
    wall, cpu = time.perf_counter() - t0, cpu_seconds() - cpu0
    done = result.summary.rows.done
    assert done == n and result.summary.rows.infra_error == 0, result.summary.rows
    return {"requests": n, "wall_s": wall, "rps": n / wall, "cpu_ms": 1000 * cpu / n, "peak_rss_mb": peak_rss_mib()}


def write_samples(data: Path, path: Path, n: int) -> None:
    """The first ``n`` instances' frame files and sentences, for the inspect_ai child."""
    path.write_text(json.dumps([{"frames": [str(f.file) for f in inst.frames], "sentence": inst.sentence}
                                for inst in _instances(data, n)]))


def run_inspect(samples_file: Path, out: Path, url: str, n: int, concurrency: int, images: str = "path", log_images: bool = True) -> dict:
    """One inspect_ai eval of the same ``n`` instances; its figures (imports nothing of povagent).
    ``images``: ``path`` (the PNG's path) or ``data-url`` (one data URL per file, shared by
    every sample showing it). ``log_images=False`` is inspect's ``--no-log-images``: the eval
    log keeps no copy of the frames."""
    import base64

    from inspect_ai import Task, eval
    from inspect_ai.dataset import Sample
    from inspect_ai.model import ChatMessageUser, ContentImage, ContentText
    from inspect_ai.solver import generate

    os.environ["LOOPBACK_BASE_URL"] = url
    os.environ.setdefault("LOOPBACK_API_KEY", "bench-key")
    samples = []
    data_urls: dict[str, str] = {}

    def image(frame: str) -> str:
        if images == "path":
            return frame
        if frame not in data_urls:
            data_urls[frame] = "data:image/png;base64," + base64.b64encode(Path(frame).read_bytes()).decode()
        return data_urls[frame]

    for k, inst in enumerate(json.loads(samples_file.read_text())[:n]):
        content: list = []
        for i, frame in enumerate(inst["frames"]):
            content += [ContentText(text=f"Image {i}:"), ContentImage(image=image(frame))]
        content.append(ContentText(text=f"Sentence: {inst['sentence']}\nAnswer in JSON."))
        samples.append(Sample(id=k, input=[ChatMessageUser(content=content)]))
    task = Task(dataset=samples, solver=generate())
    import openai  # noqa: F401  (imported before the clock starts, as povagent's litellm is)

    cpu0, t0 = cpu_seconds(), time.perf_counter()
    logs = eval(task, model="openai-api/loopback/bench-model", max_connections=concurrency, max_tokens=256,
                log_dir=str(out), display="none", fail_on_error=True, log_images=log_images)  # fmt: skip
    wall, cpu = time.perf_counter() - t0, cpu_seconds() - cpu0
    assert logs[0].status == "success", logs[0].status
    return {"requests": n, "wall_s": wall, "rps": n / wall, "cpu_ms": 1000 * cpu / n, "peak_rss_mb": peak_rss_mib()}


def child(args: argparse.Namespace) -> None:
    out = Path(tempfile.mkdtemp(prefix=f"bench-{args.child}-", dir=args.workdir))
    if args.child == "povagent":
        figures = run_povagent(Path(args.child_data), out, args.url, args.n, args.concurrency, args.model)
    else:
        figures = run_inspect(Path(args.child_data), out, args.url, args.n, args.concurrency, args.inspect_images,
                              not args.inspect_no_log_images)  # --child-data: the samples file
    print(json.dumps(figures))


def measure(tool: str, n: int, args: argparse.Namespace, data: Path, url: str, workdir: Path) -> dict:
    python = sys.executable
    if tool == "inspect_ai":
        python, data = args.inspect_python, workdir / "samples.json"
    done = subprocess.run(
        [python, __file__, "--child", tool, "--n", str(n), "--child-data", str(data), "--url", url,
         "--workdir", str(workdir), "--concurrency", str(args.concurrency), "--model", args.model,
         "--inspect-images", args.inspect_images, *(["--inspect-no-log-images"] if args.inspect_no_log_images else [])],
        capture_output=True, text=True,
    )  # fmt: skip
    if done.returncode != 0:
        raise SystemExit(f"{tool} with {n} requests failed:\n{done.stderr[-4000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--requests", type=int, default=256)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--concurrency", type=int, default=32)
    ap.add_argument("--memory", default="64,1024", help="request counts at which peak memory is measured (empty: none)")
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate --houses)")
    ap.add_argument("--houses", type=int, default=7, help="houses to generate when no --data is given")
    ap.add_argument("--model", default="hosted_vllm/bench-model", help="povagent's litellm model string")
    ap.add_argument("--inspect-python", default=sys.executable,
                    help="interpreter of an environment with inspect-ai (and openai >= 3.4) installed")
    ap.add_argument("--inspect-no-log-images", action="store_true",
                    help="run inspect_ai with log_images=False (its --no-log-images): its eval log keeps no frames")
    ap.add_argument("--inspect-images", choices=["path", "data-url"], default="path",
                    help="how inspect_ai is handed each frame: the PNG's path (read and encoded by inspect) or a ready data URL")
    ap.add_argument("--child", choices=["povagent", "inspect_ai"], help=argparse.SUPPRESS)
    ap.add_argument("--n", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--child-data", dest="child_data", help=argparse.SUPPRESS)
    ap.add_argument("--url", help=argparse.SUPPRESS)
    ap.add_argument("--workdir", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args)
        return
    import importlib.metadata

    from generated_frames import frame_digests, generated_dataset, start_verifying_server, stop_verifying_server

    sizes = [int(s) for s in args.memory.split(",") if s]
    with tempfile.TemporaryDirectory(prefix="povagent-vs-inspect-") as tmp:
        workdir = Path(tmp)
        data = generated_dataset(args.data, workdir, houses=args.houses)
        write_samples(data, workdir / "samples.json", max([args.requests, *sizes]))
        digests = frame_digests(data, workdir / "frames.sha256")
        print(f"dataset {data}: {len(digests)} generated PNGs "
              f"(mean {sum(p.stat().st_size for p in digests.values()) / len(digests) / 1024:.0f} KB)")
        server, url = start_verifying_server(workdir / "frames.sha256")
        try:
            inspect_version = subprocess.run([args.inspect_python, "-c", "import inspect_ai; print(inspect_ai.__version__)"],
                                             capture_output=True, text=True, check=True).stdout.strip()
            print(f"povagent ({args.model}, litellm {importlib.metadata.version('litellm')}) vs inspect_ai "
                  f"{inspect_version} | {args.requests} requests of {FRAMES} inline frames | "
                  f"concurrency {args.concurrency} | {args.rounds} rounds | inspect_ai handed frames as {args.inspect_images}")
            print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
            print(f"{'round':>5} {'povagent req/s':>15} {'inspect req/s':>14} {'ratio':>6}   "
                  f"{'CPU ms/req povagent':>19} {'inspect':>8}")
            rounds = []
            for r in range(args.rounds):
                order = ["povagent", "inspect_ai"] if r % 2 == 0 else ["inspect_ai", "povagent"]
                got = {tool: measure(tool, args.requests, args, data, url, workdir) for tool in order}
                p, i = got["povagent"], got["inspect_ai"]
                rounds.append((p, i))
                print(f"{r:>5} {p['rps']:>15.2f} {i['rps']:>14.2f} {p['rps'] / i['rps']:>5.2f}x   "
                      f"{p['cpu_ms']:>19.1f} {i['cpu_ms']:>8.1f}", flush=True)
            memory = {tool: {n: measure(tool, n, args, data, url, workdir) for n in sizes} for tool in ("povagent", "inspect_ai")}
            print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        finally:
            checked = stop_verifying_server(server)
            print(f"server: {checked.get('requests')} requests, {checked.get('images_fetched')} images checked against the "
                  f"dataset's SHA-256s, {checked.get('image_failures')} refused")
    ratios = [p["rps"] / i["rps"] for p, i in rounds]
    print()
    print(f"median requests/s: povagent {statistics.median(p['rps'] for p, _ in rounds):.2f}, "
          f"inspect_ai {statistics.median(i['rps'] for _, i in rounds):.2f}")
    print(f"median client CPU per request: povagent {statistics.median(p['cpu_ms'] for p, _ in rounds):.1f} ms, "
          f"inspect_ai {statistics.median(i['cpu_ms'] for _, i in rounds):.1f} ms")
    print(f"povagent / inspect_ai (median of per-round ratios): {statistics.median(ratios):.2f}x "
          f"(rounds: {', '.join(f'{x:.2f}' for x in ratios)})  goal >= 1.5x: "
          f"{'met' if statistics.median(ratios) >= 1.5 else 'NOT met'}")
    cpu_ratios = [i["cpu_ms"] / p["cpu_ms"] for p, i in rounds]
    print(f"inspect_ai / povagent client CPU per request (median of per-round ratios): {statistics.median(cpu_ratios):.2f}x "
          f"(rounds: {', '.join(f'{x:.2f}' for x in cpu_ratios)})")
    for tool, by_n in memory.items():
        if not sizes:
            break
        figures = ", ".join(f"{n} requests {by_n[n]['peak_rss_mb']:.0f} MB" for n in sizes)
        growth = by_n[sizes[-1]]["peak_rss_mb"] / by_n[sizes[0]]["peak_rss_mb"]
        print(f"peak RSS {tool}: {figures} (x{growth:.2f} from {sizes[0]} to {sizes[-1]})")


if __name__ == "__main__":
    main()
