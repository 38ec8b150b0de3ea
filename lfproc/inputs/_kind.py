"""Swapped inputs: a capture given as the white image, a white image given as the capture.

* **A capture given as the white image** (``lfproc calibrate``, ``--white``): in a white image every micro
  image repeats its neighbour; a capture's micro images carry scene texture. The texture ratio of the
  calibration (`lfproc.calibrate.texture_ratio`, over the whole image) and the largest of the per-tile
  ratios (`lfproc.calibrate.lattice_texture`, which also catches a capture whose texture fills only part
  of the frame) must stay at or below `TEXTURE_LIMIT` (0.04; white images measure 0.000–0.008 with noise,
  vignetting and 8-bit quantisation, the bundled sample's capture 0.05 overall and 0.11 in its most
  textured tile).
* **A white image given as the capture**: decoded (and devignetted), a white image is a smooth field of
  lens brightnesses with no scene in it. The per-lens brightness (mean over the views that carry light)
  is compared with its own 5 × 5-lens median: where the 99th percentile of the relative difference over
  the interior lenses stays below `WHITE_FLATNESS` (0.5 %), the capture shows no scene at lens resolution
  and is refused. Measured: a white image given as the capture 0.00 % (devignetted by itself, or by an
  8-bit copy: 0.06 %); captures 1.0 % (a render of a ±10 % low-contrast texture), 1.1 % (a faint distant
  grating), 5.5 % (a textured plane), 7.8 % (the bundled sample). Not recognised: a *different*, very noisy
  frame of a white image (shot noise makes its lenses differ by more than 0.5 %).
"""

from __future__ import annotations

import numpy as np

from ..errors import LfprocError

#: texture ratio above which a "white image" is refused as a capture of a scene
TEXTURE_LIMIT = 0.04
#: 99th percentile of the lens-to-neighbourhood brightness difference below which a capture is a white image
WHITE_FLATNESS = 0.005


def check_white_is_white(source: str, image, cfa: str, grid, global_ratio: float | None = None) -> None:
    """Refuse a white image that carries scene texture (module docstring)."""
    from ..calibrate import lattice_texture

    tiles = lattice_texture(image, cfa, grid)
    worst = max([float(global_ratio or 0.0), *(float(t) for t in tiles)])
    if worst > TEXTURE_LIMIT:
        raise LfprocError(f"{source}: this is a capture of a scene, not a white image: its micro images differ from "
                          f"their neighbours (texture ratio {worst:.2f}, a white image gives < {TEXTURE_LIMIT}); "
                          f"give a white image (a uniform bright surface, e.g. through a diffuser) as WHITE")


def lens_flatness(views: np.ndarray, view_mask=None) -> float:
    """The 99th percentile of |S / median5x5(S) − 1| over the interior lit lenses of a decoded light field,
    S the per-lens brightness (mean over the views that carry light); ``inf`` where too few lenses tell."""
    from scipy import ndimage

    views = np.asarray(views)
    m = views.shape[0]
    mask = np.ones((m, m), bool) if view_mask is None else np.asarray(view_mask, bool)
    brightness = views[mask].mean(axis=(0, 3), dtype=np.float64)      # (Ny, Nx)
    ny, nx = brightness.shape
    if ny < 9 or nx < 9:
        return float("inf")
    trend = ndimage.median_filter(brightness, size=5, mode="nearest")[2:-2, 2:-2]
    bright = brightness[2:-2, 2:-2]
    top = float(np.percentile(trend, 95))
    lit = trend > 0.05 * top
    if not top > 0 or lit.sum() < 25:
        return float("inf")
    return float(np.percentile(np.abs(bright[lit] / trend[lit] - 1.0), 99))


def check_capture_is_not_white(source: str, views: np.ndarray, view_mask=None) -> None:
    """Refuse a decoded "capture" that is a white image (module docstring)."""
    flatness = lens_flatness(views, view_mask)
    if flatness < WHITE_FLATNESS:
        raise LfprocError(f"{source}: this looks like a white image, not a capture: decoded, its lenses show a smooth "
                          f"field with no scene ({100 * flatness:.2f} % lens-to-lens variation, captures show "
                          f">= {100 * WHITE_FLATNESS:.1f} %); pass the capture as RAW and the white image as --white")
