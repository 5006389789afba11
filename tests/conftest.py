"""Test configuration: strict rank promotion, named tolerances, data locations."""

import os
from pathlib import Path

import jax
import pytest

jax.config.update("jax_numpy_rank_promotion", "raise")

REPO = Path(__file__).resolve().parents[1]
DATA = REPO / "data"
SHARED_HDR = REPO.parent / "shared" / "data" / "hdr"

RTOL32 = 1e-4
RTOL64 = 1e-6


def shared_file(name: str) -> Path:
    """A file from ../shared/data/hdr; the test is skipped (reported) when it is absent."""
    p = SHARED_HDR / name
    if not p.exists():
        pytest.skip(f"{p} not available (only in the development checkout)")
    return p


@pytest.fixture
def x64():
    """Enable float64 for the duration of a test."""
    old = jax.config.jax_enable_x64
    jax.config.update("jax_enable_x64", True)
    try:
        yield
    finally:
        jax.config.update("jax_enable_x64", old)


os.environ.setdefault("HDRJAX_CACHE", "0")
