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

#: (module, C source) of each compiled loop, under povagent/generate/.
COMPILED_LOOPS = (
    ("povagent.generate._png_rows", "povagent/generate/png_rows.c"),
    ("povagent.generate._shading", "povagent/generate/shading.c"),
    ("povagent.generate._visible_face", "povagent/generate/visible_face.c"),
)

IEEE_FLAGS = [] if sys.platform == "win32" else ["-O3", "-ffp-contract=off", "-fno-fast-math", "-fno-math-errno", "-fno-trapping-math", "-std=c99"]

setup(ext_modules=[Extension(name, [source], extra_compile_args=IEEE_FLAGS, optional=True) for name, source in COMPILED_LOOPS])
