"""Print an OpenBLAS kernel other than the one this machine picks, that its CPU can run.

``threadpoolctl`` reports the kernel OpenBLAS chose (``architecture``); a second pass of the
numeric tests under another one (``OPENBLAS_CORETYPE``) proves that they assert what is
well-posed, not digits a kernel's rounding decides. A kernel the CPU cannot execute would
crash (AVX-512 on a CPU without it), so the choice follows the CPU's flags: Haswell (AVX2,
FMA) unless that is the machine's own, then SkylakeX (AVX-512) where the CPU has it, else
Sandybridge (AVX without FMA).
"""

from __future__ import annotations

from pathlib import Path

import threadpoolctl


def own_kernel() -> str:
    """The kernel OpenBLAS picked here ("" when numpy's BLAS is not OpenBLAS)."""
    for lib in threadpoolctl.threadpool_info():
        if lib.get("internal_api") == "openblas":
            return str(lib.get("architecture") or "")
    return ""


def cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    for line in text.splitlines():
        if line.startswith("flags"):
            return set(line.split(":", 1)[1].split())
    return set()


def other_kernel(own: str, flags: set[str]) -> str:
    """Another kernel than ``own`` this CPU runs ("" when there is none worth running)."""
    if own.lower() != "haswell" and {"avx2", "fma"} <= flags:
        return "Haswell"
    if "avx512f" in flags and own.lower() != "skylakex":
        return "SkylakeX"
    if "avx" in flags and own.lower() != "sandybridge":
        return "Sandybridge"
    return ""


if __name__ == "__main__":
    import numpy  # noqa: F401  (loads numpy's OpenBLAS, which threadpoolctl then sees)

    print(other_kernel(own_kernel(), cpu_flags()))
