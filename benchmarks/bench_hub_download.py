"""Benchmark of fetching the release from a Hub: what a Given-only run saves, and the offline reopen.

Run: ``python benchmarks/bench_hub_download.py [--data FOLDER | --houses 12]``. Serves a dataset
made by ``povagent generate`` (``--data``, or ``--houses`` houses of 30 frames generated first: the
release's shape and its kind of rendered PNGs) from the loopback Hub (:mod:`povagent.testing.hub_server`) and fetches it with
``povagent download``'s function into a fresh Hugging Face cache: the whole release, then
Given-only into another cache, then the whole release again offline. Prints files, MiB and
seconds of each, and the share of bytes a Given-only run fetches.

``--rounds N`` also prices povagent's checks (every value the server sends checked, every file's
size and hash compared with the tree listing, every path confined to the cache): in N
interleaved rounds it fetches the whole release into fresh caches with povagent and with plain
:func:`huggingface_hub.snapshot_download` (which checks none of that), alternating which goes
first, and prints the median seconds of each and their ratio. Everything stays on 127.0.0.1 and
in a temporary folder.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from generated_frames import generated_dataset

from povagent.dataset.hub import download_release, release_size
from povagent.testing.hub_server import HubServer


def fetch(server: HubServer, cache: Path, **kw) -> tuple[int, float, float]:
    """(files, MiB, seconds) of one download into ``cache``."""
    t = time.perf_counter()
    release = download_release(endpoint=server.url, cache_dir=cache, progress=False, **kw)
    seconds = time.perf_counter() - t
    files, size = release_size(release.root)
    return files, size / 2**20, seconds


def plain_fetch(server: HubServer, cache: Path) -> float:
    """Seconds of huggingface_hub's own snapshot_download of the whole release into ``cache``."""
    from huggingface_hub import snapshot_download
    from tqdm.auto import tqdm

    class Silent(tqdm):  # no progress bars in a measurement
        def __init__(self, *args, **kwargs) -> None:
            kwargs["disable"] = True
            super().__init__(*args, **kwargs)

    t = time.perf_counter()
    snapshot_download(server.repo_id, repo_type="dataset", endpoint=server.url, cache_dir=cache, tqdm_class=Silent)
    return time.perf_counter() - t


def compare(server: HubServer, tmp: Path, rounds: int) -> None:
    """Interleaved rounds of povagent's checked download and plain snapshot_download."""
    ours: list[float] = []
    plain: list[float] = []
    for i in range(rounds):
        order = ("ours", "plain") if i % 2 == 0 else ("plain", "ours")
        for who in order:
            cache = tmp / f"cmp_{who}_{i}"
            if who == "ours":
                ours.append(fetch(server, cache)[2])
            else:
                plain.append(plain_fetch(server, cache))
    a, b = statistics.median(ours), statistics.median(plain)
    print(f"{rounds} interleaved rounds, whole release: povagent (checked) {a:.2f} s, "
          f"snapshot_download (unchecked) {b:.2f} s, ratio {a / b:.2f}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="a dataset made by `povagent generate` (default: generate --houses)")
    ap.add_argument("--houses", type=int, default=12, help="houses to generate without --data (the release has 47)")
    ap.add_argument("--rounds", type=int, default=0, help="interleaved rounds against plain snapshot_download (0: none)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = generated_dataset(args.data, Path(tmp), houses=args.houses)
        houses = sorted(p.name for p in (root / "artifacts").iterdir() if p.is_dir())
        pngs = sorted(root.rglob("*.png"))
        print(f"dataset {root}: {len(houses)} houses, {len(pngs)} generated PNGs of "
              f"{sum(p.stat().st_size for p in pngs) / len(pngs) / 1024:.0f} KiB on average")
        with HubServer(root, max_lifetime_s=3600) as server:
            full = fetch(server, Path(tmp) / "cache_full")
            given = fetch(server, Path(tmp) / "cache_given", conditions=["c"])
            if args.rounds:
                compare(server, Path(tmp), args.rounds)
        offline = fetch(server, Path(tmp) / "cache_full", offline=True)
    for name, (files, mib, seconds) in (("all conditions", full), ("Given only", given), ("offline reopen", offline)):
        print(f"{name:16s} {files:6d} files {mib:8.1f} MiB {seconds:7.2f} s")
    print(f"Given-only fetches {100 * given[1] / full[1]:.1f}% of the bytes ({100 * given[0] / full[0]:.1f}% of the files)")


if __name__ == "__main__":
    main()
