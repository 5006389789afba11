"""Large arrays without page faults: :func:`tune_memory`.

On Linux with glibc, JAX on CPU gets every buffer above 32 MiB (a 4096² RGB image is
200 MB) from a fresh ``mmap``, and each of its pages faults on first write, about 2 µs per
4 KiB page: 40–60 ms of every call that makes such an image, more than the arithmetic of
most operators. Two settings keep freed buffers for reuse instead:

- glibc's ``M_MMAP_THRESHOLD`` and ``M_TRIM_THRESHOLD`` at :data:`KEEP_BYTES` (``mallopt``):
  buffers up to that size come from the heap, and freed memory up to that size stays in the
  process for the next buffer;
- synchronous dispatch on CPU (``jax_cpu_enable_async_dispatch`` off): compiled functions
  run in the calling thread, whose heap serves them. With asynchronous dispatch they run in
  XLA's worker threads, whose glibc arenas cannot hold buffers above 64 MiB and map them
  afresh on every call.

Measured on the 2-core development machine (``benchmarks/bench_memory.py``, each setting in a
fresh process): Reinhard 2002 on a 4096² RGB image 111 → 39.7 ms, a 5×5 mean filter
206 → 74.8 ms, TMQI of a 2048×1024 pair 107 → 66.5 ms. The tiled 5×5 median of a 4096² image
went from 247 to 176 ms in a run by hand (synchronous dispatch loses the overlap of one
tile's copy-out with the next tile's computation, and still wins).

The cost: the process keeps up to :data:`KEEP_BYTES` of freed memory, and JAX calls on CPU
return when their result is ready. The command line tunes its own process; a program or
notebook calls :func:`tune_memory` once, before its first JAX computation (the dispatch
setting is read when JAX starts its CPU backend). ``HDRJAX_ALLOCATOR=system`` leaves both
settings alone (for the command line too).
"""

import ctypes
import os
import platform
import sys

KEEP_BYTES = 1 << 30
"""Buffers up to this size (1 GiB) are kept and reused; larger ones are mapped and unmapped
as before (a 15000² RGB float32 image is 2.7 GB)."""

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3  # glibc's malloc.h


def _glibc_mallopt():
    if not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc":
        return None
    try:
        return ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return None


def tune_memory(*, synchronous: bool = True) -> dict[str, bool]:
    """Keep freed buffers of up to :data:`KEEP_BYTES` for reuse (module docstring): large
    outputs and temporaries then cost no page faults, 2–3× faster calls on 4096² images.

    Call it once, before the first JAX computation of the process. Process-wide: the
    allocator setting applies to all of the process's memory, and ``synchronous`` (default)
    makes every JAX call on CPU return when its result is ready.

    Args:
        synchronous: also turn JAX's asynchronous CPU dispatch off (needed for buffers
            above 64 MiB; see the module docstring).

    Returns:
        ``{"allocator": ..., "synchronous": ...}``: what was applied. Nothing is, where
        ``HDRJAX_ALLOCATOR=system`` is set; the allocator setting only with glibc.
    """
    done = {"allocator": False, "synchronous": False}
    if os.environ.get("HDRJAX_ALLOCATOR", "").strip().lower() == "system":
        return done
    mallopt = _glibc_mallopt()
    if mallopt is not None:
        done["allocator"] = bool(mallopt(_M_MMAP_THRESHOLD, KEEP_BYTES)) and bool(
            mallopt(_M_TRIM_THRESHOLD, KEEP_BYTES)
        )
    if synchronous:
        import jax

        jax.config.update("jax_cpu_enable_async_dispatch", False)
        done["synchronous"] = True
    return done


__all__ = ["KEEP_BYTES", "tune_memory"]
