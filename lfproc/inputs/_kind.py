"""Swapped inputs: a capture given as the white image, a white image given as the capture.

* **A capture given as the white image** (``lfproc calibrate``, ``--white``): in a white image every micro
  image repeats its neighbour; a capture's micro images carry scene texture. The largest of the per-tile
  texture ratios over the well-lit micro images (`lfproc.calibrate.lattice_texture`, which also catches
  a capture whose texture fills only part of the frame) must stay at or below `TEXTURE_LIMIT` (0.04;
  white images measure 0.0005–0.008 with noise, hot pixels, vignetting with a sharp rim cut and 8-bit
  quantisation, the bundled sample's capture 0.11 in its most textured tile, the Lytro sample's 0.067).
  A capture whose micro images hardly differ from their neighbours (a textured plane far from the
  focus, 0.015) is not recognised.
* **A white image given as the capture**: decoded (and devignetted), a white image is a smooth field with
  no scene in it. Each view is a pinhole image of the scene, sharp at every depth, so a capture shows its
  scene in every view at lens resolution. For the central view and the four views halfway to the rim, the
  99th percentile of |V / median5x5(V) − 1| over the interior lenses is taken (`lens_flatness`); where
  the median of these stays below `WHITE_FLATNESS` (0.5 %) the capture shows no scene and is refused.
  Measured on renders of the sample's camera: a white image given as the capture 0.00 % (devignetted by
  itself) and 0.13 % (an 8-bit copy, heavy shot noise); captures 1.4 % (a faint distant grating, ±10 %),
  2.5 % (a ±10 % low-contrast texture), 9.8–14 % (noisy or textured planes), 57 % (the bundled sample).
  Not recognised: a *different*, very noisy frame of a white image (8.9 %: its noise reads as a scene).
"""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError

#: texture ratio above which a "white image" is refused as a capture of a scene
TEXTURE_LIMIT = 0.04
#: fewest lenses per side of a light field judged by `lens_flatness` (a crop of a few lenses may be uniform)
MIN_LENSES_PER_SIDE = 20
#: 99th percentile of the lens-to-neighbourhood brightness difference below which a capture is a white image
WHITE_FLATNESS = 0.005


def check_white_is_white(source: str, image, cfa: str, grid) -> None:
    """Refuse a white image that carries scene texture (module docstring)."""
    from ..calibrate import lattice_texture

    worst = max([0.0, *(float(t) for t in lattice_texture(image, cfa, grid))])
    if worst > TEXTURE_LIMIT:
        raise LfprocError(f"{source}: this is a capture of a scene, not a white image: its micro images differ from "
                          f"their neighbours (texture ratio {worst:.2f}, a white image gives < {TEXTURE_LIMIT}); "
                          f"give a white image (a uniform bright surface, e.g. through a diffuser) as WHITE")


def lens_flatness(views: np.ndarray, view_mask=None) -> float:
    """How much a decoded light field's views vary from lens to lens (module docstring).

    For the central view and the four views halfway to the rim (those that carry light), the 99th
    percentile of |V / median5x5(V) − 1| over the interior lit lenses (channels averaged); the median of
    these. Each view is a pinhole image of the scene, sharp at every depth, so scene detail shows at lens
    resolution however far the scene is from the focus plane. ``inf`` where too few lenses tell (fewer than
    `MIN_LENSES_PER_SIDE` per side).
    """
    from scipy import ndimage

    views = np.asarray(views)
    m = views.shape[0]
    mask = np.ones((m, m), bool) if view_mask is None else np.asarray(view_mask, bool)
    c, h = (m - 1) // 2, max(1, (m - 1) // 4)
    chosen = [(ky, kx) for ky, kx in ((c, c), (c - h, c), (c + h, c), (c, c - h), (c, c + h)) if mask[ky, kx]]
    if not chosen or min(views.shape[2:4]) < MIN_LENSES_PER_SIDE:
        return float("inf")
    stack = np.stack([views[ky, kx].mean(axis=-1) for ky, kx in chosen]).astype(np.float32)   # (V, Ny, Nx)
    trend = ndimage.median_filter(stack, size=(1, 5, 5), mode="nearest")[:, 2:-2, 2:-2]
    inner = stack[:, 2:-2, 2:-2]
    values = []
    for view, level in zip(inner, trend):
        top = float(np.percentile(level, 95))
        lit = level > 0.05 * top
        if top > 0 and lit.sum() >= 25:
            values.append(float(np.percentile(np.abs(view[lit] / level[lit] - 1.0), 99)))
    return float(np.median(values)) if values else float("inf")


def check_capture_is_not_white(source: str, views: np.ndarray, view_mask=None) -> None:
    """Refuse a decoded "capture" that is a white image (module docstring)."""
    flatness = lens_flatness(views, view_mask)
    if flatness < WHITE_FLATNESS:
        raise LfprocError(f"{source}: this looks like a white image, not a capture: decoded, its lenses show a smooth "
                          f"field with no scene ({100 * flatness:.2f} % lens-to-lens variation, captures show "
                          f">= {100 * WHITE_FLATNESS:.1f} %); pass the capture as RAW and the white image as --white")
