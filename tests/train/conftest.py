"""Datasets the training-export tests plant problems in: copies of the generated release."""

from __future__ import annotations

import shutil
import struct
import zlib
from collections.abc import Callable
from pathlib import Path

import pytest


def _copy_house(source: Path, root: Path, name: str) -> Path:
    """Copy the house folder ``source`` into ``root/artifacts`` as ``name`` (pair file renamed)."""
    target = root / "artifacts" / name
    shutil.copytree(source, target)
    if name != source.name:
        (target / f"{source.name}.json").rename(target / f"{name}.json")
    return target


def png_chunk(kind: bytes, data: bytes) -> bytes:
    """One PNG chunk with its checksum."""
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _bomb_png(width: int = 100_000, height: int = 100_000) -> bytes:
    """A small, well-formed PNG whose header claims ``width`` x ``height`` pixels."""
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + png_chunk(b"IEND", b"")


@pytest.fixture
def dataset_copy(generated_release: Path, tmp_path: Path) -> Callable[..., Path]:
    """``dataset_copy(name="copy", houses=None)``: the generated release copied under ``tmp_path``
    (``houses`` maps new house names to the generated house they copy; default: both as they are)."""

    def make(name: str = "copy", houses: dict[str, str] | None = None) -> Path:
        root = tmp_path / name
        (root / "artifacts").mkdir(parents=True)
        shutil.copy(generated_release / "meta.json", root / "meta.json")
        originals = sorted(p.name for p in (generated_release / "artifacts").iterdir() if p.is_dir())
        for new, old in (houses or {h: h for h in originals}).items():
            _copy_house(generated_release / "artifacts" / old, root, new)
        return root

    return make


@pytest.fixture(scope="session")
def copy_house() -> Callable[[Path, Path, str], Path]:
    """``copy_house(source, root, name)``: a house folder copied into ``root/artifacts`` as ``name``."""
    return _copy_house


@pytest.fixture(scope="session")
def bomb_png() -> Callable[..., bytes]:
    """``bomb_png(width, height)``: a small well-formed PNG claiming that many pixels."""
    return _bomb_png
