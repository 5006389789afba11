"""``hdrjax.tune_memory``: large JAX outputs reuse freed memory instead of faulting in
fresh pages on every call, and the command line tunes its own process.

Page faults are counted (``getrusage``), not timed: each call makes a 96 MB image, 24 576
pages of 4 KiB. In a default process the median call faults in most of them (its buffer
comes from a fresh ``mmap`` in an XLA worker thread); after ``tune_memory`` almost none."""

import json
import os
import platform
import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc",
    reason="the allocator setting is glibc's (mallopt); elsewhere tune_memory only switches"
    " JAX to synchronous dispatch",
)

CALLS = """
import json, resource, sys
import hdrjax
done = hdrjax.tune_memory() if sys.argv[1] == "tuned" else None
import jax, jax.numpy as jnp
x = jnp.ones((2048, 4096, 3), jnp.float32)
f = jax.jit(lambda v: v * 2.0 + 1.0)
per_call = []
for _ in range(7):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    jax.block_until_ready(f(x))
    per_call.append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
faults = sorted(per_call)[3]  # the median call (the first ones grow the heap)
print(json.dumps({"faults": faults, "done": done,
                  "async": jax.config.read("jax_cpu_enable_async_dispatch")}))
"""
PAGES = 2048 * 4096 * 3 * 4 // 4096


def _run(mode: str, **env: str) -> dict:
    environ = {k: v for k, v in os.environ.items() if k != "HDRJAX_ALLOCATOR"}
    out = subprocess.run(
        [sys.executable, "-c", CALLS, mode],
        capture_output=True,
        text=True,
        check=True,
        env={**environ, **env},
    ).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_tuned_processes_reuse_large_buffers():
    default, tuned = _run("default"), _run("tuned")
    assert default["faults"] > 0.5 * PAGES, default  # what tune_memory is for
    assert tuned["done"] == {"allocator": True, "synchronous": True}
    assert tuned["async"] is False
    assert tuned["faults"] < 0.02 * PAGES, tuned


def test_system_allocator_opts_out():
    res = _run("tuned", HDRJAX_ALLOCATOR="system")
    assert res["done"] == {"allocator": False, "synchronous": False}
    assert res["async"] is True
    assert res["faults"] > 0.5 * PAGES


def test_the_command_line_tunes_its_own_process(tmp_path):
    code = (
        "import sys, jax; from hdrjax.cli import main; sys.argv = ['hdrjax', 'info', sys.argv[1]];"
        " code = main(); print('async', jax.config.read('jax_cpu_enable_async_dispatch'));"
        " sys.exit(code)"
    )
    src = os.path.join(os.path.dirname(__file__), "..", "..", "data", "cornell_box.exr")
    out = subprocess.run(
        [sys.executable, "-c", code, src], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip().splitlines()[-1] == "async False"
