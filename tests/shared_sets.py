"""A generated set made once a test run, however many pytest-xdist workers ask for it."""

from __future__ import annotations

import fcntl
import os
from collections.abc import Callable
from pathlib import Path

import pytest


def made_once(tmp_path_factory: pytest.TempPathFactory, name: str, make: Callable[[Path], object]) -> Path:
    """``<basetemp>/<name>/POVBench``, made by ``make(root)`` unless its ``meta.json`` is there.

    Under pytest-xdist each worker's basetemp is a folder of one shared root: the folder goes
    there, so the workers make the set once between them (the first under the lock, the others
    waiting for it, then reading its files) instead of once each. ``meta.json`` is what a
    generator writes last, renamed into place: a set without it is unfinished, and ``make``
    resumes it."""
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    root = shared / name / "POVBench"
    root.parent.mkdir(parents=True, exist_ok=True)
    with open(root.parent / "generating.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not (root / "meta.json").exists():
            make(root)
    return root
