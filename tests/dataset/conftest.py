"""Fixtures for hostile-dataset tests: helpers to
edit a dataset copy's JSON (``dataset_copy`` is in tests/conftest.py), and a record of every file the process opens (Python's audit hooks), so a test
can show that a file outside the dataset was never read."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any, Callable

import pytest

_opened: list[str] | None = None
_hooked = False


def _record_open(event: str, args: tuple[Any, ...]) -> None:
    if event == "open" and _opened is not None and isinstance(args[0], (str, bytes, Path)):
        _opened.append(str(Path(args[0].decode() if isinstance(args[0], bytes) else args[0]).absolute()))


@pytest.fixture
def opened_files() -> Any:
    """Absolute paths of the files opened while the test runs (audit event ``open``)."""
    global _opened, _hooked
    if not _hooked:  # an audit hook cannot be removed: install it once, only when asked for
        sys.addaudithook(_record_open)
        _hooked = True
    _opened = []
    try:
        yield _opened
    finally:
        _opened = None



class DatasetEditor:
    """Edits a writable dataset copy: ``edit(house, change, name=None)`` rewrites a house's
    pair file (or its file ``name``) through ``change``, which edits the data in place or returns
    new data; NaN and Infinity are written as JSON's non-standard literals."""

    def __init__(self, root: Path) -> None:
        self.root = root

    def path(self, house: str, name: str | None = None) -> Path:
        """A house's pair file (``name=None``) or another of its files."""
        return self.root / "artifacts" / house / (name or f"{house}.json")

    def edit(self, house: str, change: Callable[[Any], Any], name: str | None = None) -> None:
        """Rewrite one JSON file of ``house`` through ``change``."""
        path = self.path(house, name)
        data = json.loads(path.read_text(encoding="utf-8"))
        new = change(data)
        path.write_text(json.dumps(data if new is None else new), encoding="utf-8")


@pytest.fixture
def editor(dataset_copy) -> DatasetEditor:
    """A :class:`DatasetEditor` on ``dataset_copy``."""
    return DatasetEditor(dataset_copy)
