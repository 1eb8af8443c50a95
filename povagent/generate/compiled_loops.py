"""The renderer's compiled loops (C extensions built at install), or ``None`` for numpy's path.

What it is for: a rendered view is a few dozen passes over every pixel (which face it shows,
its shading, its PNG row filters). numpy makes each pass a separate sweep over megabytes of
arrays; a C loop does them pixel by pixel in one sweep. Each loop is one C file beside the
module it speeds up (``setup.py`` lists them), doing the same IEEE operations in the same order
as that module's numpy code, which stays as the reference and as the path taken where no C
compiler was found at install: a frame is the same bytes either way
(``tests/generate/test_compiled_loops.py`` renders with both and compares).

``POVAGENT_PURE_NUMPY=1`` (read when a module first asks) takes numpy's path although the loops
are built: to compare the two, or to rule the C code out when a frame looks wrong.
What it must not do: decide anything itself; a module asks for its loop and falls back to numpy
when it gets ``None``.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

#: The environment variable that turns the compiled loops off.
PURE_NUMPY = "POVAGENT_PURE_NUMPY"
#: Every compiled loop's module name under povagent.generate (setup.py builds the same list).
LOOPS = ("_png_rows", "_shading", "_visible_face")


def compiled_loop(name: str) -> ModuleType | None:
    """The compiled module ``povagent.generate.<name>``, or ``None`` where it was not built or
    ``POVAGENT_PURE_NUMPY`` is set."""
    if name not in LOOPS:
        raise ValueError(f"{name!r} is not one of the compiled loops {LOOPS}")
    if os.environ.get(PURE_NUMPY, "") not in ("", "0"):
        return None
    try:
        return importlib.import_module(f"povagent.generate.{name}")
    except ImportError:
        return None


def built_loops() -> dict[str, bool]:
    """Which compiled loops this install has (whatever ``POVAGENT_PURE_NUMPY`` says)."""
    found = {}
    for name in LOOPS:
        try:
            importlib.import_module(f"povagent.generate.{name}")
            found[name] = True
        except ImportError:
            found[name] = False
    return found
