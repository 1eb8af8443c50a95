"""Check: a generated set and a rendered view are the same bytes on three kinds of machine.

    python benchmarks/bytes_across_cpus.py

Runs ``tests/generate/cpu_bytes_child.py`` (a one-house set of seed 11 with 3 frames and one
rendered view, every file's SHA-256) in three child processes, with the settings of
:func:`povagent.testing.embree_isa.cpu_settings`: as installed; the lowest embree ISA with
numpy at its x86-64-v2 baseline and OpenBLAS's oldest kernel; and the highest ISA below this
machine's own with numpy's AVX-512 off and OpenBLAS Haswell (AVX2 under AVX-512, the kind of
machine the bytes once differed on). Every file must equal the installed run's. The test suite
runs the first two and pins their digest (``tests/generate/test_bytes_across_cpus.py``); this
adds the third. Prints the files that differ per setting and the installed run's digest (the
test's ``PINNED``); exits 1 if any differ. Needs a C compiler (the embree shim).
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from povagent.testing.embree_isa import build_shim, cpu_settings

CHILD = Path(__file__).resolve().parent.parent / "tests" / "generate" / "cpu_bytes_child.py"


def digests_under(out: Path, env: dict[str, str]) -> dict[str, str]:
    """The child's SHA-256 of every file, run with ``env`` over an environment cleared of the
    variables the settings set."""
    base = {k: v for k, v in os.environ.items() if not k.startswith(("NPY_", "OPENBLAS_", "POVAGENT_TEST_EMBREE"))}
    done = subprocess.run([sys.executable, str(CHILD), str(out)], env={**base, **env}, capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        raise SystemExit(f"error: the child failed under {env}: {done.stderr[-2000:]}")
    return json.loads(done.stdout)


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        settings = cpu_settings(build_shim(folder / "shim"))
        results = {name: digests_under(folder / f"set{k}", env) for k, (name, env) in enumerate(settings.items())}
    reference = results["as installed"]
    failures = 0
    for name, digests in results.items():
        differing = sorted(k for k in reference.keys() | digests.keys() if reference.get(k) != digests.get(k))
        failures += bool(differing)
        print(f"{name}: {'same bytes' if not differing else f'{len(differing)} files differ: {differing[:10]}'}")
    print(f"digest as installed: {hashlib.sha256(json.dumps(reference, sort_keys=True).encode()).hexdigest()}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
