"""Run a test on a module's compiled loop and on its numpy path (the same results)."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import shutil
import subprocess
import sysconfig
from collections.abc import Callable, Iterator
from pathlib import Path
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



def generic_build(folder: Path, source: str, extra: tuple[str, ...] = ()) -> ModuleType:
    """``povagent/generate/<source>.c`` built again with setup.py's flags and
    ``-DPOVAGENT_ONE_BUILD``: the loops for any x86-64 alone (no AVX, AVX2 or AVX-512 path chosen
    at load), or with ``extra`` flags (``-mavx2``: the loops as the AVX2 clone compiles them, for
    a machine that would choose AVX-512), as module ``_<source>`` from ``folder``."""
    root = Path(__file__).resolve().parents[2]
    tree = ast.parse((root / "setup.py").read_text())
    flags = next(node.value for node in ast.walk(tree) if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "IEEE_FLAGS")
    assert isinstance(flags, ast.IfExp)
    target = folder / f"_{source}{sysconfig.get_config_var('EXT_SUFFIX')}"
    compiler = shutil.which("cc") or shutil.which("gcc")
    assert compiler is not None
    command = [compiler, "-shared", "-fPIC", *ast.literal_eval(flags.orelse), "-DPOVAGENT_ONE_BUILD", *extra, f"-I{sysconfig.get_paths()['include']}"]
    subprocess.run([*command, str(root / "povagent" / "generate" / f"{source}.c"), "-o", str(target)], check=True, capture_output=True, timeout=120)
    spec = importlib.util.spec_from_file_location(f"_{source}", target)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def cpu_has(feature: str) -> bool:
    """Whether this CPU has ``feature`` (numpy's name for it: ``"AVX2"``, ``"AVX512F"``)."""
    try:
        umath = importlib.import_module("numpy._core._multiarray_umath")
    except ImportError:  # numpy 1
        umath = importlib.import_module("numpy.core._multiarray_umath")
    return bool(umath.__cpu_features__.get(feature, False))


#: The builds a loop is compared against the installed one in: every clone's code but the
#: installed machine's own (for any x86-64; AVX2's, where the machine would choose AVX-512).
OTHER_BUILDS = pytest.mark.parametrize("extra", [(), ("-mavx2",)], ids=["any-x86-64", "avx2"])


_BUILT: dict[tuple[str, tuple[str, ...]], ModuleType] = {}


def other_build(folder: Path, source: str, extra: tuple[str, ...]) -> ModuleType:
    """:func:`generic_build` with ``extra`` (into the first asking test's ``folder``, then kept
    for the session's other tests: the same source, the same module), skipped where this CPU
    could not run it."""
    if "-mavx2" in extra and not cpu_has("AVX2"):
        pytest.skip("this CPU has no AVX2")
    if (source, extra) not in _BUILT:
        _BUILT[source, extra] = generic_build(folder, source, extra)
    return _BUILT[source, extra]
