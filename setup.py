"""The compiled loops of the renderer (C, optional): everything else is in pyproject.toml.

Each extension is one C file beside the Python module whose numpy passes it replaces, with the
same IEEE operations in the same order, so a frame is the same bytes either way
(``povagent/generate/compiled_loops.py`` loads them; ``tests/generate/test_compiled_loops.py``
holds the two paths equal). ``optional=True``: where no C compiler is found the install goes on
and the numpy path runs, the same bytes, slower.

The flags keep the arithmetic IEEE: no fused multiply-add contraction (``-ffp-contract=off``:
GCC fuses ``a * b + c`` by default where the CPU has FMA, which rounds once instead of twice)
and no value-changing optimizations (``-fno-fast-math``). Two flags that change no value let the
compiler vectorize loops with choices and square roots: ``-fno-math-errno`` (``sqrt`` of a negative
number need not set ``errno``, so it is one instruction, not a test and a call) and
``-fno-trapping-math`` (both sides of a choice may be computed: only the floating-point exception
flags, which no loop reads, could tell). They come after ``-fno-fast-math``, which resets them.
"""

from __future__ import annotations

import sys

from setuptools import Extension, setup

#: (module, C sources, the files they include) of each compiled loop, under povagent/generate/.
COMPILED_LOOPS = (
    ("povagent.generate._png_rows", ["png_rows.c"], ["vector_clones.h"]),
    ("povagent.generate._shading", ["shading.c"], ["vector_clones.h"]),
    # (visible_face.c includes its two other files: one translation unit)
    ("povagent.generate._visible_face", ["visible_face.c"], ["visible_face.h", "visible_face_rays.c", "visible_face_outline.c", "vector_clones.h"]),
)

IEEE_FLAGS = [] if sys.platform == "win32" else ["-O3", "-ffp-contract=off", "-fno-fast-math", "-fno-math-errno", "-fno-trapping-math", "-std=c99"]


def compiled_loop(name: str, sources: list[str], headers: list[str]) -> Extension:
    """One optional extension; the files its sources include are ``depends`` (a changed one
    rebuilds it, and the source distribution carries them: MANIFEST.in)."""
    folder = "povagent/generate/"
    return Extension(name, [folder + f for f in sources], depends=[folder + f for f in headers], extra_compile_args=IEEE_FLAGS, optional=True)


setup(ext_modules=[compiled_loop(*loop) for loop in COMPILED_LOOPS])
