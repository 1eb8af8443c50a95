"""What the frame cache saves: a VSI-Bench scene's frames sampled with and without it.

    python benchmarks/bench_frame_cache.py [--seconds 30] [--frames 32] [--rounds 3]

A scene video is written once (``--seconds`` at 30 fps, 640x480, H.264 as ``libx264`` writes it
at its default quality: a textured wall panned past the camera with a camera's sensor noise on
every frame, so the stream weighs what a phone's walk-through does, a few Mbit/s, and the
decoder works as on one). Then, each in a fresh process (so no import or decoder state carries over),
the ``--frames`` frames VSI-Bench's models see are sampled
(:func:`povagent.dataset.frame_cache.cached_sample_frames`) three ways:

* ``no cache``: decoded, nothing kept (what every run did before the cache);
* ``first run``: an empty cache folder: decoded, and the entry written;
* ``second run``: the same folder: the video's bytes hashed and the entry's frames copied out.

Each figure is the CPU time (user + system) of the call alone, the median over ``--rounds``
rounds, with the videos each opened with PyAV (:func:`povagent.dataset.video_frames.videos_opened`).
Writes ``benchmarks/results/bench_frame_cache.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from results_file import figure, record

WIDTH, HEIGHT, FPS = 640, 480, 30

CHILD = """
import json, resource, sys
from pathlib import Path
from povagent.dataset import video_frames
from povagent.dataset.frame_cache import FrameCache, cached_sample_frames
video, n, out, kept = Path(sys.argv[1]), int(sys.argv[2]), Path(sys.argv[3]), sys.argv[4]
cache = FrameCache(Path(kept)) if kept else None
import av, PIL.Image  # imported before the clock starts: the call is what is measured
def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
start, opened = cpu(), video_frames.videos_opened()
files = cached_sample_frames(video, n, out, cache)
print(json.dumps({"cpu_s": cpu() - start, "opened": video_frames.videos_opened() - opened, "frames": len(files)}))
"""


def write_video(path: Path, seconds: int) -> Path:
    """A walk past a textured wall: a fixed texture panned across the frame, one step a frame,
    with fresh sensor noise on each frame (what keeps a real video's bitrate up)."""
    import av
    import numpy as np

    rng = np.random.default_rng(0)
    wall = (rng.integers(0, 255, size=(HEIGHT // 8, 4 * WIDTH // 8, 3), dtype=np.uint8)).repeat(8, axis=0).repeat(8, axis=1)
    shade = np.linspace(0.6, 1.0, wall.shape[1], dtype=np.float32)[None, :, None]
    wall = (wall * shade).astype(np.uint8)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=FPS)
        stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "yuv420p"
        for i in range(seconds * FPS):
            x = (4 * i) % (wall.shape[1] - WIDTH)
            noisy = wall[:, x : x + WIDTH].astype(np.int16) + rng.integers(-12, 13, size=(HEIGHT, WIDTH, 1), dtype=np.int16)
            frame = av.VideoFrame.from_ndarray(np.clip(noisy, 0, 255).astype(np.uint8), format="rgb24")
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def measure(video: Path, n: int, out: Path, kept: Path | None) -> dict:
    """One sampling in a fresh interpreter: its CPU seconds, the videos it opened, the frames it wrote."""
    shutil.rmtree(out, ignore_errors=True)
    done = subprocess.run([sys.executable, "-c", CHILD, str(video), str(n), str(out), str(kept or "")], check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=int, default=30)
    parser.add_argument("--frames", type=int, default=32)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-frame-cache-"))
    try:
        video = write_video(work / "scene.mp4", args.seconds)
        print(f"video: {args.seconds} s, {WIDTH}x{HEIGHT} at {FPS} fps, {video.stat().st_size / 1e6:.1f} MB", flush=True)
        runs: dict[str, list[dict]] = {"no cache": [], "first run": [], "second run": []}
        for k in range(args.rounds):
            kept = work / f"kept-{k}"
            runs["no cache"].append(measure(video, args.frames, work / "out", None))
            runs["first run"].append(measure(video, args.frames, work / "out", kept))
            runs["second run"].append(measure(video, args.frames, work / "out", kept))
            print(f"round {k + 1}: " + ", ".join(f"{name} {r[-1]['cpu_s']:.3f} s CPU ({r[-1]['opened']} opened)" for name, r in runs.items())
                  + f"; load {os.getloadavg()[0]:.2f}", flush=True)  # fmt: skip
        cpu = {name: statistics.median(r["cpu_s"] for r in rs) for name, rs in runs.items()}
        opened = {name: rs[-1]["opened"] for name, rs in runs.items()}
        setting = f"{args.seconds} s {WIDTH}x{HEIGHT} H.264 video, {args.frames} frames"
        figures = [
            figure("sampling without the cache", round(cpu["no cache"], 3), "s CPU", comparison=f"{setting}; {opened['no cache']} video opens"),
            figure("first run (decode and keep)", round(cpu["first run"], 3), "s CPU", comparison=f"{setting}; {opened['first run']} video opens"),
            figure("second run (from the cache)", round(cpu["second run"], 3), "s CPU", target="no video decoded",
                   comparison=f"{setting}; {opened['second run']} video opens"),
            figure("second run / first run", round(cpu["second run"] / cpu["first run"], 4), "ratio"),
        ]  # fmt: skip
        for f in figures:
            print(f"{f['name']}: {f['value']} {f['unit']}")
        record("bench_frame_cache", figures)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
