"""Houses are generated in parallel by default, one worker per core the process may use."""

from __future__ import annotations

import os

from povagent.generate.dataset import default_jobs


def test_one_worker_per_usable_core_and_never_more_than_the_houses():
    cores = len(os.sched_getaffinity(0))
    assert default_jobs(3) == min(3, cores)
    assert default_jobs(1) == 1
    assert default_jobs(1000) == cores


def test_a_process_pinned_to_one_core_generates_in_one_process():
    # a child forked from this one pins itself to one core and asks: a real process of its own,
    # without a second interpreter to start and import povagent into (about 0.4 s of CPU)
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: only this thread runs here, and it leaves by os._exit
        code = 1
        try:
            os.close(read)
            os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
            os.write(write, f"{len(os.sched_getaffinity(0))} {default_jobs(3)}".encode())
            code = 0
        finally:
            os._exit(code)
    os.close(write)
    with os.fdopen(read) as answer:
        said = answer.read()
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0, said
    assert said == "1 1"
