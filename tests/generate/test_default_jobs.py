"""Houses are generated in parallel by default, one worker per core the process may use."""

from __future__ import annotations

import os
import subprocess
import sys

from povagent.generate.dataset import default_jobs


def test_one_worker_per_usable_core_and_never_more_than_the_houses():
    cores = len(os.sched_getaffinity(0))
    assert default_jobs(3) == min(3, cores)
    assert default_jobs(1) == 1
    assert default_jobs(1000) == cores


def test_a_process_pinned_to_one_core_generates_in_one_process():
    code = "import os; os.sched_setaffinity(0, {min(os.sched_getaffinity(0))}); from povagent.generate.dataset import default_jobs; print(default_jobs(3))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "1"
