"""The visible contrast distortion of a rendition (Mantiuk, Daly & Kerofsky 2008).

The quantity display-adaptive tone mapping minimises, as a metric of any rendition: how
far the transducer responses to the contrasts of the scene (seen at its adaptation
luminance) are from those to the same contrasts shown on a given display, summed over the
scene's contrast statistics in four frequency bands (paper Eq. 9–10, with Daly's CSF and
the contrast-masking transducer, Eq. 11). Lower is better; ``mantiuk2008``'s own rendition
is the minimum over global tone curves for its display.

Numeric contract: ``hdr`` linear RGB in cd/m² (absolute); ``ldr`` display-encoded values in
[0, 1] for a gamma–gain–offset display; result in squared JND units per counted contrast.

Reference: R. Mantiuk, S. Daly, L. Kerofsky, "Display adaptive tone mapping", ACM
Transactions on Graphics 27(3):68, 2008, https://doi.org/10.1145/1360612.1360667.
"""

import jax
from jaxtyping import Array, ArrayLike, Float

from ..operators import Mantiuk2008
from ._common import image_pair


def contrast_distortion(
    hdr: Float[ArrayLike, "*batch H W 3"],
    ldr: Float[ArrayLike, "*batch H W 3"],
    *,
    display: str = "lcd",
    peak: float | None = None,
    black: float | None = None,
    gamma: float | None = None,
    ambient: float | None = None,
    reflectivity: float | None = None,
    enhancement: float = 1.0,
    scene_luminance: float | None = 1000.0,
    visual_model: str = "full",
) -> Float[Array, "*batch"]:
    """Visible contrast distortion of the rendition ``ldr`` of the scene ``hdr``.

    Args:
        hdr: the scene, linear RGB in cd/m².
        ldr: its rendition, display-encoded values in [0, 1] (the shape of ``hdr``).
        display: a display of ``mantiuk2008`` (``"lcd"`` γ 2.2, 200 cd/m², black 0.8 cd/m²,
            60 lx; ``"lcd_office"``, ``"lcd_bright"``, ``"crt"``, ``"gog"``); ``peak``,
            ``black`` (cd/m²), ``gamma``, ``ambient`` (lx) and ``reflectivity`` override it.
        enhancement: factor on the scene contrasts the display should reproduce.
        scene_luminance: adaptation luminance of the scene (cd/m²); ``None``: each
            contrast's own background.
        visual_model: ``"full"``, ``"none"`` or a comma list of ``luminance_masking``,
            ``contrast_masking``, ``csf``.

    Returns:
        The distortion, ``*batch``: ``Σ N (T(ΔY, S(Y)) − T(e G, S(L_a)))² / Σ N`` over the
        scene's contrasts (:meth:`hdrjax.operators.Mantiuk2008.visible_distortion`), where
        the rendition's tone curve is the mean display luminance at each scene luminance.
        Differentiable with respect to ``ldr`` (the scene's statistics are constants).
    """
    a, b = image_pair(hdr, ldr, ("hdr", "ldr"))
    op = Mantiuk2008(
        display=display,
        peak=peak,
        black=black,
        gamma=gamma,
        ambient=ambient,
        reflectivity=reflectivity,
        contrast_enhancement=enhancement,
        scene_luminance=scene_luminance,
        visual_model=visual_model,
    )
    fn = op.visible_distortion
    for _ in range(a.ndim - 3):
        fn = jax.vmap(fn)
    return fn(a, b)
