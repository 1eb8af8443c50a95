"""Run a test on a module's compiled loop and on its numpy path (the same results)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from types import ModuleType

import pytest

from povagent.generate.compiled_loops import compiled_loop


def each_path(module: ModuleType, attribute: str = "_COMPILED") -> Callable[..., Iterator[str]]:
    """A fixture body (``request.param``: ``"compiled"`` or ``"numpy"``) setting ``module``'s
    compiled loop for the test: the built extension, or ``None`` for numpy's path. Where the loop
    was not built the compiled case is skipped; ``tests/generate/test_compiled_loops.py`` fails
    instead wherever a C compiler was there to build it."""

    def fixture(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
        if request.param == "compiled":
            loop = compiled_loop(module._LOOP)
            if loop is None:
                pytest.skip(f"{module.__name__}'s compiled loop {module._LOOP} is not built here (or POVAGENT_PURE_NUMPY is set)")
            monkeypatch.setattr(module, attribute, loop)
        else:
            monkeypatch.setattr(module, attribute, None)
        yield request.param

    return fixture

