"""What the speed benchmarks share: a dataset made by ``povagent generate`` and a loopback
server that checks every image it receives is one of that dataset's frames.

Speed figures come from requests carrying the release's own kind of frames (512x512 PNGs
rendered by the generator, ~200-300 KB each), never synthetic ones: a cheaper image makes a
cheaper request, and the figures would flatter whoever builds requests. The server
(``python -m povagent.testing.loopback_server --expect-sha256 FILE``) decodes every image of
every request, answers 400 to one whose SHA-256 is not a frame of the dataset, and reports on
exit how many it checked.
"""

from __future__ import annotations

import hashlib
import json
import signal
import subprocess
import sys
from pathlib import Path


def povagent_command() -> list[str]:
    """The ``povagent`` console script of this interpreter's environment."""
    script = Path(sys.executable).with_name("povagent")
    return [str(script)] if script.exists() else [sys.executable, "-m", "povagent.cli"]


def generated_dataset(data: Path | None, workdir: Path, houses: int, seed: int = 0) -> Path:
    """``data`` when given (a folder ``povagent generate`` wrote), else ``houses`` new houses of
    30 frames each under ``workdir``."""
    if data is not None:
        if not (data / "meta.json").exists():
            raise SystemExit(f"{data}: not a dataset written by `povagent generate` (no meta.json)")
        return data
    out = workdir / "POVBench"
    print(f"generating {houses} house(s) of 30 frames with `povagent generate` (seed {seed})...", flush=True)
    subprocess.run([*povagent_command(), "generate", "--out", str(out), "--houses", str(houses), "--frames", "30",
                    "--seed", str(seed)], check=True, stdout=subprocess.DEVNULL)  # fmt: skip
    return out


def frame_digests(data: Path, path: Path) -> dict[str, Path]:
    """Write the SHA-256 of every PNG of ``data`` to ``path`` (one a line); digest -> file."""
    digests = {hashlib.sha256(p.read_bytes()).hexdigest(): p for p in sorted(data.rglob("*.png"))}
    path.write_text("\n".join(digests) + "\n")
    return digests


def start_verifying_server(
    digests_file: Path,
    lifetime_s: float = 7200,
    count_bodies: bool = False,
    delay_s: float = 0.0,
    reply: str | None = None,
    extra: tuple[str, ...] = (),
) -> tuple[subprocess.Popen, str]:
    """The loopback server in its own process, refusing any image not in ``digests_file``; with
    ``count_bodies`` it also counts every request body by its SHA-256 (reported on stop); each
    answer (``reply``, else the server's default) after ``delay_s``; ``extra``: more of its options."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--lifetime", str(lifetime_s),
         "--expect-sha256", str(digests_file), *(["--count-bodies"] if count_bodies else []),
         "--delay", str(delay_s), *(["--reply", reply] if reply is not None else []), *extra],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    url = proc.stdout.readline().strip()  # type: ignore[union-attr]
    if not url.startswith("http://127.0.0.1:"):
        proc.kill()
        raise SystemExit(f"loopback server did not start (printed {url!r})")
    return proc, url


def stop_verifying_server(proc: subprocess.Popen) -> dict:
    """Stop the server; its count of requests, images checked and images refused (and, when it
    counted them, of request bodies by SHA-256)."""
    proc.send_signal(signal.SIGINT)
    try:
        out, _ = proc.communicate(timeout=300)  # a loaded machine: it finishes what it holds first
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
    lines = [line for line in out.splitlines() if line.startswith("{")]
    return json.loads(lines[-1]) if lines else {}
