"""Run a process with embree forced to one instruction set, to compare bytes across CPUs.

What it is for: embree picks its kernels (SSE2, AVX, AVX2, AVX-512) for the CPU at hand, and
embreex hands ``rtcNewDevice`` no configuration through which to choose. A tiny preloaded
shim, compiled here with the machine's C compiler, passes ``isa=...`` (or any configuration)
from the environment to embree, so one machine can render as machines of other kinds would
(``tests/generate/test_bytes_across_cpus.py``, ``benchmarks/bytes_across_cpus.py``,
``benchmarks/bench_render_isa.py``). What it must not do: touch the process that calls it
(only the environment it returns is changed).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

#: The shim: ``rtcNewDevice`` with the configuration ``POVAGENT_TEST_EMBREE_CONFIG`` names.
SHIM_SOURCE = r"""
#include <dlfcn.h>
#include <stdlib.h>
typedef void *RTCDevice;
RTCDevice rtcNewDevice(const char *cfg) {
    static RTCDevice (*real)(const char *) = 0;
    if (!real) {
        void *lib = dlopen(getenv("POVAGENT_TEST_EMBREE_LIB"), RTLD_NOW | RTLD_NOLOAD);
        if (!lib) lib = dlopen(getenv("POVAGENT_TEST_EMBREE_LIB"), RTLD_NOW);
        if (!lib) abort();
        real = (RTCDevice (*)(const char *))dlsym(lib, "rtcNewDevice");
        if (!real) abort();
    }
    const char *forced = getenv("POVAGENT_TEST_EMBREE_CONFIG");
    return real(forced ? forced : cfg);
}
"""


def embree_library() -> Path:
    """The libembree4 bundled with the embreex wheel."""
    import embreex

    found = sorted((Path(embreex.__file__).parent.parent / "embreex.libs").glob("libembree4*.so*"))
    if not found:
        raise FileNotFoundError("the embreex wheel's bundled libembree4 was not found beside it (embreex.libs/)")
    return found[0]


def build_shim(folder: Path) -> Path:
    """Compile the shim into ``folder``; its path."""
    compiler = shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise FileNotFoundError("a C compiler (cc) is needed to force embree's instruction set")
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "embree_isa.c").write_text(SHIM_SOURCE)
    out = folder / "embree_isa.so"
    subprocess.run([compiler, "-shared", "-fPIC", "-o", str(out), str(folder / "embree_isa.c"), "-ldl"], check=True, timeout=120)
    return out


def isa_environment(shim: Path, isa: str) -> dict[str, str]:
    """The environment entries that make a child's embree use ``isa`` (sse2, sse4.2, avx, avx2, avx512)."""
    return {"LD_PRELOAD": str(shim), "POVAGENT_TEST_EMBREE_LIB": str(embree_library()), "POVAGENT_TEST_EMBREE_CONFIG": f"isa={isa}"}


def cpu_isas() -> list[str]:
    """The embree instruction sets this CPU runs, lowest first."""
    flags: set[str] = set()
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("flags"):
            flags = set(line.split(":", 1)[1].split())
            break
    isas = ["sse2", "sse4.2"]
    if {"avx", "avx2", "fma"} <= flags:
        isas += ["avx", "avx2"]
    if {"avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl"} <= flags:
        isas.append("avx512")
    return isas


#: numpy's dispatch targets above the x86-64-v2 baseline, and the AVX-512 ones alone
#: (``NPY_DISABLE_CPU_FEATURES`` values).
NUMPY_V2_ONLY = "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"
NUMPY_NO_AVX512 = "X86_V4 AVX512_ICL AVX512_SPR"


def cpu_settings(shim: Path) -> dict[str, dict[str, str]]:
    """Three kinds of machine, by name, as child environments, in this order: as installed; the
    lowest embree ISA with numpy at its x86-64-v2 baseline and OpenBLAS's oldest kernel; and the
    highest ISA below this machine's own with numpy's AVX-512 off and OpenBLAS Haswell (the kind
    of machine the bytes once differed on: AVX2 under AVX-512)."""
    isas = cpu_isas()
    forced = [(isas[0], NUMPY_V2_ONLY, "Prescott"), (isas[-2], NUMPY_NO_AVX512, "Haswell")]
    settings: dict[str, dict[str, str]] = {"as installed": {}}
    for isa, numpy, blas in forced:
        settings[f"embree {isa}, numpy off: {numpy}, OpenBLAS {blas}"] = {
            **isa_environment(shim, isa), "NPY_DISABLE_CPU_FEATURES": numpy, "OPENBLAS_CORETYPE": blas}
    return settings
