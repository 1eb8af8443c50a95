"""What a ``GroundingAgent`` command costs over a robot's keyframes, before and after frames
were kept encoded with their keyframes (issue 44, item 1).

    python benchmarks/bench_agent_frames.py [--rounds 3] [--commands 10] [--baseline f33d9c8]

Thirty 640x480 keyframes (a smooth pattern with sensor-like noise, different per frame) are
asked about, in a fresh interpreter per measurement, by today's code and by the ``povagent``
package of commit ``--baseline`` (:mod:`baseline_code`), alternating round by round so both
see the same load. CPU time (``time.process_time``, every thread of the process) of:

* ``first``: one ``locate`` over the 30 keyframes with a backend that sends pixels (an
  in-process backend that asks the image store for each image's data URL, as a remote
  model's request does, and answers the centre);
* ``second``: the same command again over the same, unchanged keyframes (the ROS session
  hands the agent each keyframe's ``shown`` frame; before, the bare arrays); goal: <= 0.15x
  ``first``;
* ``arrays_first`` / ``arrays_second``: the same two commands over 30 other frames handed in as
  bare numpy arrays (the agent's documented input), the second with equal arrays (copies);
  ``files_first`` / ``files_second``: the same over those frames saved as 640x480 PNG files;
  goal: second <= 0.15x first (issue 55, goal 3);
* ``center_first``: one command with the offline ``center`` baseline over 30 fresh arrays (a
  backend that never reads pixels: nothing to letterbox or encode);
* ``ros_center``: one command through the ROS session (:class:`~povagent.ros.session.GroundingSession`)
  over a full memory of 30 keyframes with the offline ``center`` baseline, the mean of
  ``--commands`` commands after the first; goal: under 40 ms.

Prints each figure per round and the medians, with the load average; writes
``benchmarks/results/bench_agent_frames.json``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from pathlib import Path

from baseline_code import baseline_checkout, cpu_of
from results_file import figure, record

KEYS = ("first", "second", "ros_center", "arrays_first", "arrays_second", "files_first", "files_second", "center_first")

SNIPPET = r"""
import time
import numpy as np
from povagent import hookimpl
from povagent.agent import GroundingAgent
from povagent.exchange.messages import Response
from povagent.interfaces import Backend
from povagent.geometry.goals import PinholeCamera
from povagent.plugins import get_plugin_host
from povagent.ros.keyframes import Keyframe
from povagent.ros.session import GroundingSession, agent_locate

W, H, N = 640, 480, 30
rng = np.random.default_rng(0)
yy, xx = np.mgrid[0:H, 0:W]

def frame(i):
    base = np.stack([np.sin(xx / (37.0 + i)) , np.cos(yy / (23.0 + i)), np.sin((xx + yy) / (51.0 + 2 * i))], axis=-1)
    pixels = 110 + 90 * base + rng.normal(0, 4, size=(H, W, 3))
    return np.clip(pixels, 0, 255).astype(np.uint8)

class SendsPixels(Backend):
    cacheable = False
    def identity(self):
        return {"backend": "sends-pixels"}
    async def complete(self, request, images):
        for h in request.image_hashes():
            images.data_url(h)
        return Response(text='{"selected_image": 0, "x": 256, "y": 256}')

class Plugin:
    @hookimpl
    def register_backends(self, register):
        register("sends-pixels", SendsPixels)

host = get_plugin_host()
host.add_plugin(Plugin(), name="bench-sends-pixels")
camera = PinholeCamera.from_fov(np.eye(4), 60.0, W, H)
keyframes = [Keyframe(10**9 * (i + 1), frame(i), camera, None, "cam") for i in range(N)]
shown = [getattr(k, "shown", k.rgb) for k in keyframes]  # what the ROS session hands the agent

with GroundingAgent("sends-pixels", parser="json") as agent:
    agent.locate("warm-up", [frame(99)])
    t = time.process_time(); agent.locate("the mug is right of the kettle", shown)
    print("first=", time.process_time() - t)
    t = time.process_time(); agent.locate("the phone is left of the sofa", shown)
    print("second=", time.process_time() - t)
    arrays = [frame(i + 100) for i in range(N)]
    t = time.process_time(); agent.locate("the mug is right of the kettle", arrays)
    print("arrays_first=", time.process_time() - t)
    again = [a.copy() for a in arrays]
    t = time.process_time(); agent.locate("the phone is left of the sofa", again)
    print("arrays_second=", time.process_time() - t)
    from PIL import Image
    import tempfile, os
    folder = tempfile.mkdtemp()
    files = [os.path.join(folder, f"frame_{i}.png") for i in range(N)]
    for i, path in enumerate(files):
        Image.fromarray(frame(i + 200)).save(path)
    t = time.process_time(); agent.locate("the mug is right of the kettle", files)
    print("files_first=", time.process_time() - t)
    t = time.process_time(); agent.locate("the phone is left of the sofa", files)
    print("files_second=", time.process_time() - t)

with GroundingAgent("center") as agent:
    agent.locate("warm-up", [frame(98)])
    fresh = [frame(i + 300) for i in range(N)]
    t = time.process_time(); agent.locate("the mug is right of the kettle", fresh)
    print("center_first=", time.process_time() - t)

with GroundingAgent("center") as agent:
    session = GroundingSession(agent_locate(agent))
    session.memory.restore([Keyframe(10**9 * (i + 1), frame(i + 40), camera, None, "cam") for i in range(N)])
    session.answer("warm-up")
    t = time.process_time()
    for i in range({commands}):
        result = session.answer(f"command {i}")
    assert result.status.value in ("ok", "no_goal"), result
    print("ros_center=", (time.process_time() - t) / {commands})
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--commands", type=int, default=10)
    parser.add_argument("--baseline", default="f33d9c8", help="the commit measured as 'before'")
    args = parser.parse_args()
    code = SNIPPET.replace("{commands}", str(args.commands))
    with tempfile.TemporaryDirectory() as tmp:
        old = baseline_checkout(args.baseline, Path(tmp) / "baseline")
        print(f"load before: {os.getloadavg()}")
        got: dict[str, list[dict[str, float]]] = {"before": [], "after": []}
        for r in range(args.rounds):
            order = (("before", old), ("after", None)) if r % 2 == 0 else (("after", None), ("before", old))
            for label, path in order:
                got[label].append(cpu_of(code, path))
            b, a = got["before"][-1], got["after"][-1]
            print(f"round {r + 1}: " + "; ".join(
                f"{k}: before {1000 * b[k]:.1f} ms, after {1000 * a[k]:.1f} ms" for k in KEYS))
    med = {label: {k: statistics.median(m[k] for m in runs) for k in KEYS} for label, runs in got.items()}
    b, a = med["before"], med["after"]
    second_over_first = statistics.median(m["second"] / m["first"] for m in got["after"])
    ratio = {kind: {label: statistics.median(m[f"{kind}_second"] / m[f"{kind}_first"] for m in got[label]) for label in got}
             for kind in ("arrays", "files")}
    for kind in ("arrays", "files"):
        print(f"{kind}: second / first before {ratio[kind]['before']:.3f}, after {ratio[kind]['after']:.3f} (goal <= 0.15)")
    print(f"center first command: before {1000 * b['center_first']:.1f} ms, after {1000 * a['center_first']:.1f} ms")
    load = os.getloadavg()
    print(f"medians (CPU ms): before first {1000 * b['first']:.1f}, second {1000 * b['second']:.1f}, ROS center {1000 * b['ros_center']:.1f}")
    print(f"                  after  first {1000 * a['first']:.1f}, second {1000 * a['second']:.1f}, ROS center {1000 * a['ros_center']:.1f}")
    print(f"after: second / first = {second_over_first:.3f} (goal <= 0.15); ROS center {1000 * a['ros_center']:.1f} ms (goal < 40); load after: {load}")
    setting = "30 keyframes of 640x480, letterboxed to 512x512"
    record("bench_agent_frames", [
        figure("second command over unchanged keyframes / first", round(second_over_first, 3), "x", target="<= 0.15",
               comparison=f"{setting}; a backend that sends pixels (data URLs); CPU time, median of {args.rounds} rounds"),
        figure("first command, CPU", round(1000 * a["first"], 1), "ms", comparison=f"before (commit {args.baseline}): {1000 * b['first']:.1f} ms"),
        figure("second command, CPU", round(1000 * a["second"], 1), "ms", comparison=f"before (commit {args.baseline}): {1000 * b['second']:.1f} ms"),
        figure("ROS command with the center baseline, CPU", round(1000 * a["ros_center"], 1), "ms", target="< 40",
               comparison=f"before (commit {args.baseline}): {1000 * b['ros_center']:.1f} ms; GroundingSession.answer over a full memory"),
        *(figure(f"second command with the same {what} / first", round(ratio[kind]["after"], 3), "x", target="<= 0.15",
                 comparison=f"before (commit {args.baseline}): {ratio[kind]['before']:.3f}x; {setting}, handed in as {what}; "
                 f"first {1000 * a[kind + '_first']:.1f} ms, second {1000 * a[kind + '_second']:.1f} ms")
          for kind, what in (("arrays", "numpy arrays"), ("files", "640x480 PNG files"))),
        figure("first command with the center baseline over 30 fresh arrays, CPU", round(1000 * a["center_first"], 1), "ms",
               comparison=f"before (commit {args.baseline}): {1000 * b['center_first']:.1f} ms; a backend that reads no pixels"),
    ])


if __name__ == "__main__":
    main()
