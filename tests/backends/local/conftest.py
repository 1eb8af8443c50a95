"""Tiny checkpoints for the in-process backend's tests, built once per session (no download).

Skipped as a whole when torch or transformers is missing (``pip install torch==2.13.0`` then the
``test`` extra installs both): the rest of the suite does not need them.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest


@pytest.fixture(scope="session", autouse=True)
def _torch_on_one_thread() -> None:
    """Skip this folder's tests when torch or transformers is missing; else run torch's
    operators on one thread in this test process.

    Imported here, at the first of these tests, not when the folder is collected: every
    pytest-xdist worker collects every folder, and one that runs none of these tests need not
    import torch. One thread: the suite's workers share the machine's cores, and on a tiny
    checkpoint's tensors torch's OpenMP workers mostly spin-wait at their barriers: one thread
    trains and generates in the same wall time for half the CPU. No check here depends on the
    thread count."""
    torch = pytest.importorskip("torch", reason="the in-process backend's tests need torch (pip install torch==2.13.0 first)")
    pytest.importorskip("transformers")
    torch.set_num_threads(1)


@pytest.fixture(scope="session")
def tiny_root(tmp_path_factory) -> Path:
    """A folder holding the session's tiny checkpoints."""
    return tmp_path_factory.mktemp("tiny_checkpoints")


@pytest.fixture(scope="session")
def tiny_qwen(tiny_root) -> Path:
    """A Qwen2-VL-style checkpoint (its processor is remote code: trust_remote_code needed)."""
    from povagent.testing.tiny_checkpoints import build_qwen2_vl

    return build_qwen2_vl(tiny_root / "qwen2_vl")


@pytest.fixture(scope="session")
def tiny_idefics3(tiny_root) -> Path:
    """An Idefics3 checkpoint (loads without remote code)."""
    from povagent.testing.tiny_checkpoints import build_idefics3

    return build_idefics3(tiny_root / "idefics3")


@pytest.fixture(scope="session")
def tiny_pointing(tiny_root, tiny_qwen) -> Path:
    """The Qwen2-VL-style checkpoint turned into one that points like MolmoPoint."""
    from povagent.testing.tiny_checkpoints import add_point_reader

    folder = tiny_root / "pointing"
    shutil.copytree(tiny_qwen, folder)
    return add_point_reader(folder)


@pytest.fixture(scope="session")
def tiny_fits_two(tiny_root, tiny_qwen) -> Path:
    """The Qwen2-VL-style checkpoint running out of memory for batches above two requests."""
    from povagent.testing.tiny_checkpoints import add_memory_limit

    folder = tiny_root / "fits_two"
    shutil.copytree(tiny_qwen, folder)
    return add_memory_limit(folder, max_rows=2)


@pytest.fixture(scope="session")
def tiny_fits_none(tiny_root, tiny_qwen) -> Path:
    """The Qwen2-VL-style checkpoint running out of memory for every request."""
    from povagent.testing.tiny_checkpoints import add_memory_limit

    folder = tiny_root / "fits_none"
    shutil.copytree(tiny_qwen, folder)
    return add_memory_limit(folder, max_rows=0)
