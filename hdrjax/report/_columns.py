"""The table's numeric columns and its images, shared by the table and its HTML page."""

import dataclasses
import io

import numpy as np


@dataclasses.dataclass(frozen=True)
class Column:
    """A numeric column of the table: key, heading, which direction is better, meaning."""

    key: str
    label: str
    higher_is_better: bool | None
    help: str


COLUMNS = (
    Column("q", "TMQI Q", True, "tone-mapped image quality index (Yeganeh & Wang 2013), 0-1"),
    Column("s", "S", True, "TMQI structural fidelity against the HDR image, 0-1"),
    Column("n", "N", True, "TMQI statistical naturalness of the rendition, 0-1"),
    Column(
        "pu_ssim",
        "PU-SSIM",
        True,
        "SSIM of PU21-encoded display luminance against the reference rendition "
        "(Mantiuk & Azimi 2021)",
    ),
    Column(
        "clipped",
        "clipped %",
        False,
        "pixels with a channel clipped to 0 (not black in the scene) or 1",
    ),
    Column("mean_luminance", "mean L_d", None, "mean display luminance, fraction of white"),
    Column("warm_s", "warm ms", False, "median time of the compiled operator (estimation in)"),
    Column("compile_s", "compile s", False, "time to trace and compile the operator"),
    Column("fit_s", "fit s", False, "time of the fit, its compilation included"),
)
"""The numeric columns, in the order the HTML page shows them."""


def image_bytes(rendition: np.ndarray, max_size: int | None, quality: int) -> bytes:
    """A JPEG of an 8-bit rendition, downscaled to at most ``max_size`` pixels on its long
    side (``None``: as is)."""
    from PIL import Image

    im = Image.fromarray(rendition)
    if max_size is not None and max(im.size) > max_size:
        im.thumbnail((max_size, max_size), Image.Resampling.LANCZOS)
    buf = io.BytesIO()
    im.save(buf, format="JPEG", quality=quality)
    return buf.getvalue()


def milliseconds(seconds: float) -> str:
    """A time in milliseconds, three significant digits (whole ones from a second up)."""
    ms = 1e3 * seconds
    return f"{ms:.3g}" if ms < 1e3 else f"{ms:.0f}"
