"""A report's intervals have the same bits on every machine (povagent/report/statistics.py and
povagent/scoring/bootstrap.py).

The bootstrap sums every resample of every metric at once, a product of a count matrix and the
metrics' columns. Done by BLAS, that product's last bits depend on the CPU (OpenBLAS picks its
kernel by CPU: ``OPENBLAS_CORETYPE``) and on the thread count, and a report's CIs, its
``summary.json`` and CSV tables with them, would differ between two machines given the same
run folder. Each environment below stands in for another machine; the intervals must agree to
the bit with the default's.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

#: Large enough that BLAS blocks and splits the product (2,439 instances: the release's size).
CHILD = """
import numpy as np
from povagent.report.statistics import _ratio_estimates
from povagent.scoring.bootstrap import bootstrap_mean_cis
rng = np.random.default_rng(7)
n, runs = 2439, 3
metrics = [(rng.exponential(0.3, size=(n, runs)), (rng.random((n, runs)) > 0.1).astype(float)) for _ in range(4)]
for e in _ratio_estimates(metrics, 2000, 0.95, 0):
    print(e.value.hex(), e.lo.hex(), e.hi.hex())
# the choice sets' intervals: a mean's resamples gathered and summed (a float column and a 0/1 one)
for e in bootstrap_mean_cis([rng.exponential(0.3, size=n), (rng.random(n) > 0.4).astype(float)]):
    print(e.value.hex(), e.lo.hex(), e.hi.hex())
"""

MACHINES = {
    "one BLAS thread": {"OPENBLAS_NUM_THREADS": "1"},
    "four BLAS threads": {"OPENBLAS_NUM_THREADS": "4"},
    "OpenBLAS's Sandybridge kernel": {"OPENBLAS_CORETYPE": "Sandybridge"},
    "numpy without AVX2 or AVX-512": {"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL"},
}


def intervals(extra: dict[str, str]) -> str:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NPY_", "OPENBLAS_", "OMP_"))}
    done = subprocess.run([sys.executable, "-c", CHILD], env={**env, **extra}, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.fixture(scope="module")
def default_intervals() -> str:
    return intervals({})


@pytest.mark.parametrize("machine", sorted(MACHINES))
def test_the_intervals_have_the_same_bits_on_another_machine(default_intervals, machine):
    assert len(default_intervals.splitlines()) == 6
    assert intervals(MACHINES[machine]) == default_intervals
