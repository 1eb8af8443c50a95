"""Benchmark of fetching the release from a Hub: what a Given-only run saves, and the offline reopen.

Run: ``python benchmarks/bench_hub_download.py [--houses 47]``. Writes a synthetic release in the
real one's shape (30 frames a house, 288/47 pairs a house, PNGs of about the real size, 226 KiB),
serves it from the loopback Hub (:mod:`povagent.testing.hub_server`) and fetches it with
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

from povagent.dataset.hub import download_release, release_size
from povagent.testing.hub_server import HubServer
from povagent.testing.pytest_plugin import write_release

#: Rows of noise per PNG that bring a 512x512 frame to about the release's mean PNG (516 MiB / 2,332).
NOISE_ROWS = 150


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
    ap.add_argument("--houses", type=int, default=12, help="houses (the release has 47)")
    ap.add_argument("--rounds", type=int, default=0, help="interleaved rounds against plain snapshot_download (0: none)")
    args = ap.parse_args()
    pairs = max(1, round(288 * args.houses / 47))
    with tempfile.TemporaryDirectory() as tmp:
        root = write_release(
            Path(tmp) / "POVBench", houses=args.houses, pairs=pairs, pair_directions=min(4 * pairs, round(pairs * 813 / 288)),
            frames=30, noise_rows=NOISE_ROWS,
        )  # fmt: skip
        with HubServer(root, max_lifetime_s=3600) as server:
            full = fetch(server, Path(tmp) / "cache_full")
            given = fetch(server, Path(tmp) / "cache_given", conditions=["c"])
            if args.rounds:
                compare(server, Path(tmp), args.rounds)
        offline = fetch(server, Path(tmp) / "cache_full", offline=True)
    print(f"houses {args.houses}, pairs {pairs}")
    for name, (files, mib, seconds) in (("all conditions", full), ("Given only", given), ("offline reopen", offline)):
        print(f"{name:16s} {files:6d} files {mib:8.1f} MiB {seconds:7.2f} s")
    print(f"Given-only fetches {100 * given[1] / full[1]:.1f}% of the bytes ({100 * given[0] / full[0]:.1f}% of the files)")


if __name__ == "__main__":
    main()
