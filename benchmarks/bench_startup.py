"""A 1-request ``povagent run`` against a bare script making the same litellm call: wall time and CPU.

    python benchmarks/bench_startup.py [--rounds 6] [--data FOLDER] [--model openai/bench-model]

The dataset is generated first (``povagent generate --houses 1 --frames 30``: the release's
own 512x512 PNGs) unless ``--data`` names a generated one. An OpenAI-compatible loopback server
(:mod:`povagent.testing.loopback_server`) runs in this process with ``fetch_images``: it decodes
every image it receives and records its SHA-256, and each round checks that both contenders'
requests carried exactly the dataset's frames, and that their ``messages`` are identical.

Three processes are timed per round, each started fresh, in an order that alternates between
rounds (the machine is shared; rounds differ by what else runs):

* ``povagent run``: the console script on a pipeline of 1 instance (``basic`` strategy, the
  house's 30 frames inline, ``json`` parser, ``official`` scorer) into a new run folder with a
  new response cache, backend ``litellm`` with ``--model`` at the server's ``api_base``;
* ``bare litellm``: ``python -c`` importing litellm, reading the same 30 PNGs, base64-encoding
  them into the same message (checked at the server) and calling ``litellm.completion`` with the
  same model string, ``api_base`` and generation parameters, then exiting normally;
* ``povagent run, cached``: the same pipeline into another new run folder with the first run's
  response cache: every answer is cached, so no request is sent and litellm is never imported.

povagent's own modules are byte-compiled first (``compileall``), as ``pip install .`` does when
it installs the package: an editable checkout run with ``PYTHONDONTWRITEBYTECODE=1`` (a common
setting in containers) would otherwise compile ~140 modules from source in every timed run
(~0.15 s), a cost litellm's modules, installed by pip, never pay.

Wall time is from the process's start to its end (interpreter start-up and teardown included),
CPU is the child's user+system time (``os.wait4``). The ratio is taken within each round and
the median reported, with the load average before and after.
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from generated_frames import povagent_command

from povagent.testing.loopback_server import LoopbackServer

KEY_ENV = "POVAGENT_BENCH_KEY"

BARE_SCRIPT = r"""
import base64, json, os, sys
spec = json.load(open(sys.argv[1]))
import litellm
litellm.suppress_debug_info = True
messages = []
for m in spec["messages"]:
    content = m["content"]
    if isinstance(content, list):
        parts = []
        for p in content:
            if "file" in p:
                with open(p["file"], "rb") as f:
                    url = "data:image/png;base64," + base64.b64encode(f.read()).decode("ascii")
                parts.append({"type": "image_url", "image_url": {**p["image_url"], "url": url}})
            else:
                parts.append(p)
        content = parts
    messages.append({"role": m["role"], "content": content})
response = litellm.completion(model=spec["model"], api_base=spec["api_base"], api_key=os.environ["POVAGENT_BENCH_KEY"],
                              messages=messages, **spec["params"])
print(response.choices[0].message.content)
"""


def _timed(cmd: list[str], env: dict[str, str]) -> dict[str, float]:
    """Run ``cmd``; its wall time (start to end) and CPU (user + system) in seconds."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    out, err = proc.communicate(timeout=600)
    wall = time.perf_counter() - t0
    # communicate() reaped the child; its resource usage is in RUSAGE_CHILDREN's growth
    if proc.returncode != 0:
        raise SystemExit(f"{cmd[0]} exited {proc.returncode}:\n{err.decode()[-2000:]}")
    return {"wall": wall, "stdout": out.decode(), "stderr": err.decode()}


def _run_measured(cmd: list[str], env: dict[str, str]) -> dict[str, float]:
    before = os.times()
    result = _timed(cmd, env)
    after = os.times()
    result["cpu"] = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return result


def _pipeline(path: Path, data: Path, url: str, model: str, output: Path, cache: Path) -> Path:
    doc = {
        "dataset": str(data),
        "backend": {"name": "litellm", "options": {"model": model, "api_base": url, "api_key_env": KEY_ENV}},
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official"],
        "instances": {"conditions": ["a"], "limit": 1},
        "timeout": 120,
        "cache": str(cache),
        "output": str(output),
    }
    path.write_text(json.dumps(doc))  # JSON is YAML
    return path


def _byte_compile_povagent() -> list[str]:
    """Compile povagent's and its plugins' modules to ``__pycache__``, as ``pip install`` does."""
    import povagent
    import povagent_plugins

    folders = [str(Path(m.__file__).parent) for m in (povagent, povagent_plugins)]  # type: ignore[arg-type]
    subprocess.run([sys.executable, "-m", "compileall", "-q", *folders], check=True, stdout=subprocess.DEVNULL)
    return folders


def _frames_by_sha(data: Path) -> dict[str, Path]:
    return {hashlib.sha256(p.read_bytes()).hexdigest(): p for p in sorted(data.rglob("*.png"))}


def _bare_spec(body: dict, frames: dict[str, Path], url: str, model: str) -> dict:
    """The request povagent sent, with each inline image replaced by the file it came from."""
    messages = []
    for m in body["messages"]:
        content = m["content"]
        if isinstance(content, list):
            parts = []
            for p in content:
                if p.get("type") == "image_url":
                    raw = base64.b64decode(p["image_url"]["url"].split(",", 1)[1])
                    rest = {k: v for k, v in p["image_url"].items() if k != "url"}
                    parts.append({"file": str(frames[hashlib.sha256(raw).hexdigest()]), "image_url": rest})
                else:
                    parts.append(p)
            content = parts
        messages.append({"role": m["role"], "content": content})
    params = {k: body[k] for k in ("max_tokens", "temperature", "response_format", "seed") if k in body}
    return {"model": model, "api_base": url, "messages": messages, "params": params}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate one house)")
    ap.add_argument("--model", default="openai/bench-model")
    args = ap.parse_args()
    # litellm fetches its cost map from the network at import unless told not to: both contenders
    # use the bundled one (povagent sets this itself; a bare script on a closed network must too)
    env = {**os.environ, KEY_ENV: "sk-bench", "LITELLM_LOCAL_MODEL_COST_MAP": "True"}
    work = Path(tempfile.mkdtemp(prefix="bench-startup-"))
    try:
        data = args.data
        if data is None:
            data = work / "POVBench"
            subprocess.run([*povagent_command(), "generate", "--out", str(data), "--houses", "1", "--frames", "30", "--seed", "0"],
                           check=True, env=env, stdout=subprocess.DEVNULL)
        frames = _frames_by_sha(data)
        compiled = _byte_compile_povagent()
        print(f"byte-compiled {', '.join(compiled)} (as pip install does; PYTHONDONTWRITEBYTECODE="
              f"{os.environ.get('PYTHONDONTWRITEBYTECODE', 'unset')} here)")
        with LoopbackServer(reply='{"selected_image": 1, "x": 0.5, "y": 0.5}', fetch_images=True, max_lifetime_s=3600) as server:
            # one untimed run gives the request povagent sends; the bare script rebuilds it
            _run_measured(povagent_command() + ["run", "-q", str(_pipeline(work / "probe.yaml", data, server.url, args.model,
                                                                        work / "probe", work / "probe" / "cache.sqlite"))], env)
            sent = server.requests[-1]
            spec = _bare_spec(sent.body, frames, server.url, args.model)
            (work / "bare.json").write_text(json.dumps(spec))
            n_images = sum(1 for m in spec["messages"] if isinstance(m["content"], list) for p in m["content"] if "file" in p)
            print(f"dataset {data}: {len(frames)} generated PNGs; the request carries {n_images} of them inline "
                  f"({len(json.dumps(sent.body)) / 1e6:.1f} MB of JSON)")
            print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} CPUs)")
            rows: dict[str, list[dict[str, float]]] = {"run": [], "bare": [], "cached": []}
            for r in range(args.rounds):
                out, cached_out = work / f"run{r}", work / f"cached{r}"
                fresh = _pipeline(work / f"run{r}.yaml", data, server.url, args.model, out, out / "cache.sqlite")
                again = _pipeline(work / f"cached{r}.yaml", data, server.url, args.model, cached_out, out / "cache.sqlite")
                order = ["run", "bare"] if r % 2 == 0 else ["bare", "run"]
                for who in order:
                    seen = len(server.requests)
                    if who == "run":
                        rows["run"].append(_run_measured(povagent_command() + ["run", "-q", str(fresh)], env))
                    else:
                        rows["bare"].append(_run_measured([sys.executable, "-c", BARE_SCRIPT, str(work / "bare.json")], env))
                    got = server.requests[seen:]
                    assert len(got) == 1, f"{who}: {len(got)} requests reached the server"
                    assert got[0].body["messages"] == sent.body["messages"], f"{who}: its messages differ from povagent's"
                    assert [i.sha256 for i in got[0].images] == [i.sha256 for i in sent.images], f"{who}: other image bytes"
                    assert all(i.sha256 in frames for i in got[0].images), f"{who}: an image that is no dataset frame"
                seen = len(server.requests)
                rows["cached"].append(_run_measured(povagent_command() + ["run", "-q", str(again)], env))
                assert len(server.requests) == seen, "the cached re-run sent a request"
                print(f"round {r + 1}: run {rows['run'][-1]['wall']:.2f} s wall / {rows['run'][-1]['cpu']:.2f} s CPU, "
                      f"bare {rows['bare'][-1]['wall']:.2f} / {rows['bare'][-1]['cpu']:.2f}, "
                      f"cached re-run {rows['cached'][-1]['wall']:.2f} / {rows['cached'][-1]['cpu']:.2f}; "
                      f"run/bare wall {rows['run'][-1]['wall'] / rows['bare'][-1]['wall']:.2f}x", flush=True)
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        wall = [a["wall"] / b["wall"] for a, b in zip(rows["run"], rows["bare"])]
        cpu = [a["cpu"] / b["cpu"] for a, b in zip(rows["run"], rows["bare"])]
        med = {k: {m: statistics.median(x[m] for x in v) for m in ("wall", "cpu")} for k, v in rows.items()}
        print("\n| contender | wall s (median) | CPU s (median) |\n|---|---|---|")
        for k, label in (("run", "povagent run, 1 request"), ("bare", "bare litellm script"), ("cached", "povagent run, cached re-run")):
            print(f"| {label} | {med[k]['wall']:.2f} | {med[k]['cpu']:.2f} |")
        print(f"\nrun / bare, within each round: wall {statistics.median(wall):.2f}x (rounds {min(wall):.2f}-{max(wall):.2f}), "
              f"CPU {statistics.median(cpu):.2f}x (rounds {min(cpu):.2f}-{max(cpu):.2f})")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
