"""A generated set and a rendered view are the same bytes whatever the CPU's features.

The pins of ``test_active_tool_bytes.py`` once held only on the kind of machine they were made
on: embree's AVX-512 and AVX2 kernels round hit distances differently, so every frame differed.
Here one small set and one view are made in child processes that each switch off what this
machine can switch off, and every file must match the pins and each other (the suite runs the
set as installed and on the lowest kind of machine; ``benchmarks/bytes_across_cpus.py`` adds
the highest below this machine's own, AVX2 under AVX-512):

* embree's ISA (sse2 ... avx512), forced through ``rtcNewDevice``'s configuration string by a
  shim preloaded into the child (:mod:`povagent.testing.embree_isa`: embreex passes no
  configuration of its own); the shim is compiled with the C compiler the README's machine has;
* numpy's dispatch (``NPY_DISABLE_CPU_FEATURES``: x86-64-v2 baseline only, or no AVX-512);
* OpenBLAS's kernel (``OPENBLAS_CORETYPE``);
* the renderer's compiled loops (``POVAGENT_PURE_NUMPY``: the lowest machine takes numpy's
  path, as an install without a C compiler does).

What no child can switch off (another vendor's rounding of approximate instructions, another
zlib) is named in ``docs/explanation/reproducibility.md``.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from povagent.generate.compiled_loops import PURE_NUMPY
from povagent.testing.embree_isa import build_shim, cpu_isas, cpu_settings, isa_environment

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]

CHILD = Path(__file__).with_name("cpu_bytes_child.py")
#: SHA-256 of the child's JSON (every file of the set and the view's PNG, by name).
PINNED = "ac8a17569adaa1ab03828b840642acc9bad007cf667c61184508e014be85cee8"


@pytest.fixture(scope="module")
def shim(tmp_path_factory) -> Path:
    return build_shim(tmp_path_factory.mktemp("embree-shim"))


def _child(out: Path, env: dict[str, str]) -> dict[str, str]:
    base = {k: v for k, v in os.environ.items() if not k.startswith(("NPY_", "OPENBLAS_", "POVAGENT_TEST_EMBREE", PURE_NUMPY))}
    done = subprocess.run([sys.executable, str(CHILD), str(out)], env={**base, **env}, capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, f"{env}: {done.stderr[-2000:]}"
    return json.loads(done.stdout)


def test_a_generated_set_and_a_view_are_the_same_bytes_with_every_cpu_feature_switched_off(shim, tmp_path):
    # as installed (the compiled loops where they are built), and the lowest ISA with numpy at
    # its baseline, OpenBLAS's oldest kernel and numpy's path instead of the compiled loops
    settings = dict(list(cpu_settings(shim).items())[:2])
    lowest = list(settings)[1]
    settings[lowest] = {**settings[lowest], PURE_NUMPY: "1"}
    with ThreadPoolExecutor(max_workers=2) as pool:
        results = dict(zip(settings, pool.map(lambda kv: _child(tmp_path / f"set{kv[0]}", kv[1]), enumerate(settings.values()))))
    reference = results["as installed"]
    for name, digests in results.items():
        differing = sorted(k for k in reference.keys() | digests.keys() if reference.get(k) != digests.get(k))
        assert not differing, f"{name}: {differing}"
    assert hashlib.sha256(json.dumps(reference, sort_keys=True).encode()).hexdigest() == PINNED


RAW_DISTANCES = """
import hashlib, numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh
rng = np.random.default_rng(0)
scene = rtcore_scene.EmbreeScene(robust=False)
TriangleMesh(scene=scene, vertices=(rng.random((3000, 3)) * 10).astype(np.float32), indices=rng.integers(0, 3000, (3000, 3)).astype(np.int32))
d = rng.normal(size=(65536, 3)).astype(np.float32)
d /= np.sqrt((d * d).sum(axis=1))[:, None]
out = scene.run(np.tile(np.float32([5, 5, -5]), (65536, 1)), d, output=1)
print(hashlib.sha256(out["tfar"].tobytes()).hexdigest())
"""


def test_the_isas_forced_here_are_real_embree_reports_other_distances_under_them(shim):
    """What the fix is for, and proof the shim reaches embree: its own hit distances differ
    between the lowest and the highest ISA forced (so the test above compares real kernels)."""
    isas = cpu_isas()
    seen = {}
    for isa in (isas[0], isas[-1]):
        env = {**os.environ, **isa_environment(shim, isa)}
        done = subprocess.run([sys.executable, "-c", RAW_DISTANCES], env=env, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr[-2000:]
        seen[isa] = done.stdout.strip()
    assert seen[isas[0]] != seen[isas[-1]], seen
