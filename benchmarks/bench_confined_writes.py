"""What the hardening of issue 32 (items 4, 5, 7) costs on the paths it touches.

    python benchmarks/bench_confined_writes.py [--repeat N]

Each figure sets the new way beside the old one, measured in this one run on this machine:

* opening a run's journal or log to append: :func:`povagent.files.confined_write.open_inside`
  (descriptor walk, ``O_NOFOLLOW``, a hard-link check) beside ``open(path, "a")``; once per file
  and run, never per row;
* writing a ``summary.json`` whole: ``write_inside`` (aside, renamed) beside the previous
  ``tmp.write_text`` + ``os.replace``;
* removing the keys povagent knows from an answer (``Redactor.known``, one key known, a
  typical 200-character answer that holds none): per answer, beside the runner's per-instance
  overhead target (2 ms);
* reading a released 512x512 frame again with the hash check (``ImageStore._read_again``)
  beside ``Path.read_bytes`` (the re-read before) and beside the frame's first read (which
  already hashed it); only frames used again after their house was let go pay it.

Prints each figure and its ratio, and writes them to ``benchmarks/results/bench_confined_writes.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

from PIL import Image
from results_file import record

from povagent.exchange.images import ImageStore
from povagent.files.confined_write import open_inside, write_inside
from povagent.files.redaction import Redactor

#: The runner's per-instance overhead target (benchmarks/bench_runner.py).
OVERHEAD_TARGET_MS = 2.0


def best_us(fn: Callable[[], Any], repeat: int, number: int) -> float:
    """The median over ``repeat`` rounds of the mean time of ``number`` calls, in microseconds."""
    rounds = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        rounds.append((time.perf_counter() - t0) / number * 1e6)
    return statistics.median(rounds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=7, help="Rounds per figure (the median is kept).")
    args = parser.parse_args()
    load_before = os.getloadavg()
    figures: list[dict[str, Any]] = []

    with tempfile.TemporaryDirectory(prefix="povagent-confined-") as tmp:
        run = Path(tmp) / "run"
        run.mkdir()

        def confined_append() -> None:
            open_inside(run, "log.jsonl", "a").close()

        def plain_append() -> None:
            open(run / "log.jsonl", "a").close()

        new = best_us(confined_append, args.repeat, 2000)
        old = best_us(plain_append, args.repeat, 2000)
        print(f"open to append (once per file and run): confined {new:.1f} us, plain open {old:.1f} us, ratio {new / old:.2f}")
        figures.append({"name": "open to append, confined / plain", "value": round(new / old, 3), "unit": "ratio",
                        "comparison": f"open_inside(run, 'log.jsonl', 'a') {new:.1f} us beside open(path, 'a') {old:.1f} us"})

        data = json.dumps({"rows": {"answered": 2500}, "note": "x" * 4000}, indent=2)

        def confined_whole() -> None:
            write_inside(run, "summary.json", data)

        def plain_whole() -> None:
            tmp_path = run / "summary.json.tmp"
            tmp_path.write_text(data, encoding="utf-8")
            os.replace(tmp_path, run / "summary.json")

        new = best_us(confined_whole, args.repeat, 500)
        old = best_us(plain_whole, args.repeat, 500)
        print(f"write summary.json whole: confined {new:.1f} us, tmp + replace {old:.1f} us, ratio {new / old:.2f}")
        figures.append({"name": "write a file whole, confined / tmp + replace", "value": round(new / old, 3), "unit": "ratio",
                        "comparison": f"write_inside {new:.1f} us beside Path.write_text + os.replace {old:.1f} us (a 4 KB summary.json)"})

        redactor = Redactor(("lab-key-4f9a8c7e2b1d",))
        answer = 'I think the target is in frame 3. {"selected_image": 3, "x": 256, "y": 301} ' + "because " * 12
        per_answer = best_us(lambda: redactor.known(answer), args.repeat, 20000)
        share = per_answer / (OVERHEAD_TARGET_MS * 1000)
        print(f"redact known keys from an answer: {per_answer:.2f} us, {100 * share:.3f} % of the {OVERHEAD_TARGET_MS:g} ms per-instance target")
        figures.append({"name": "known-key redaction per answer, share of the per-instance overhead target", "value": round(share, 5),
                        "unit": "fraction", "target": "small beside 2 ms per instance",
                        "comparison": f"Redactor.known on a {len(answer)}-character answer, one key known: {per_answer:.2f} us"})

        frame = Path(tmp) / "frame.png"
        Image.effect_noise((512, 512), 64).convert("RGB").save(frame)
        store = ImageStore()
        store.hold_files([frame])
        info = store.add_file(frame)
        store.release_files([frame])
        size = frame.stat().st_size
        checked = best_us(lambda: store._read_again(frame, info.image_hash, size), args.repeat, 200)
        plain = best_us(frame.read_bytes, args.repeat, 200)
        print(f"read a released frame again ({size // 1024} KB): checked {checked:.1f} us, read_bytes {plain:.1f} us, ratio {checked / plain:.2f}")
        figures.append({"name": "re-read of a released frame, checked / plain", "value": round(checked / plain, 3), "unit": "ratio",
                        "comparison": f"ImageStore._read_again (regular file, size bound, SHA-256) {checked:.1f} us beside "
                                      f"Path.read_bytes {plain:.1f} us, a {size // 1024} KB 512x512 PNG"})
        first = best_us(lambda: ImageStore().add_file(frame), args.repeat, 200)
        print(f"  beside the first read of the same frame (read, PNG check, SHA-256): {first:.1f} us, ratio {checked / first:.2f}")
        figures.append({"name": "re-read of a released frame, checked / first read", "value": round(checked / first, 3), "unit": "ratio",
                        "target": "<= 1 (a re-read costs no more than the first read)",
                        "comparison": f"ImageStore._read_again {checked:.1f} us beside ImageStore.add_file on a fresh store "
                                      f"(read, PNG chunk check, SHA-256) {first:.1f} us, the same {size // 1024} KB PNG"})

    load_after = os.getloadavg()
    print(f"load average before {' '.join(f'{x:.2f}' for x in load_before)}, after {' '.join(f'{x:.2f}' for x in load_after)} "
          f"({os.cpu_count()} CPUs)")
    command = " ".join(["python benchmarks/bench_confined_writes.py", *sys.argv[1:]])
    print(f"wrote {record('bench_confined_writes', figures, command)}")


if __name__ == "__main__":
    main()
