"""XLA:CPU compiler options the filters compile with: XLA flag names, kept here only.

JAX has no public API for what these do; ``jax.jit(..., compiler_options=...)`` (public)
passes them to XLA by name. They are XLA ``DebugOptions`` fields, which XLA may rename or
drop in any release: XLA then rejects the name (``No such compile option``) and every
filter call fails at compile time instead of silently running slower.
``tests/test_filters.py`` compiles with each of them, so an upgrade that drops one fails
there, by name.

- ``xla_cpu_prefer_vector_width``: AVX-512 machines run the integer sorting networks twice
  as wide with 512-bit vectors; XLA's default prefers 256. Harmless on CPUs without
  AVX-512.
- ``xla_cpu_copy_insertion_use_region_analysis``: region analysis in copy insertion drops
  the copies XLA otherwise makes of the strip loops' carried buffers in every iteration
  (the median's loop had 4).

Applied to hdrjax's own top-level ``jit`` only: inside a caller's ``jit`` the caller's
settings win (JAX refuses options on a nested ``jit``).
"""

CPU_COMPILER_OPTIONS: dict[str, int | bool] = {
    "xla_cpu_prefer_vector_width": 512,
    "xla_cpu_copy_insertion_use_region_analysis": True,
}
"""Options for :func:`jax.jit`'s ``compiler_options`` on the CPU backend."""

__all__ = ["CPU_COMPILER_OPTIONS"]
