"""Micro image centres measured in windows of the white image, so large sensors cost what small ones do.

A white image of 41 Mpx holds some 230,000 micro images; a lattice fit needs a few thousand spread over
the sensor. The image is therefore measured in a 5 × 5 layout of windows (the whole image when all its
lenses fit `WHOLE_IMAGE_BUDGET`), each read from the white image itself: monochrome conversion, outlier repair,
flattening, candidates and sub-pixel centring (steps 1, 3 and 4) never touch a full-size copy. A
window has a margin of 3 pitches beyond its core, in which no centre is kept, so the smoothing of
step 3 sees the same neighbourhood as in the whole image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._flatten import candidate_centres, flatten
from ._monochrome import mono_window, repair_outlier_pixels
from ._symmetry_centres import refine_centres, symmetric_offsets

#: the whole image is measured when its lenses × symmetric sample pairs stay below this
WHOLE_IMAGE_BUDGET = 1_500_000
#: otherwise the windows together hold about this many lenses × pairs (bounds the time of step 4)
WINDOW_BUDGET = 150_000
#: windows per side when the image holds more lenses than the budget
WINDOWS_PER_SIDE = 5


@dataclass(frozen=True)
class Window:
    """A window ``[y0:y1, x0:x1]`` of the sensor whose centres are kept inside ``core`` (cy0, cy1, cx0, cx1)."""

    y0: int
    y1: int
    x0: int
    x1: int
    core: tuple


@dataclass(frozen=True)
class Measured:
    """Centres measured in one window, plus its flattened image (for the white-image checks).

    Attributes
    ----------
    xy : ndarray (N, 2)
        Sub-pixel centres in sensor coordinates.
    asymmetry : ndarray (N,)
        Remaining point asymmetry of each (`refine_centres`).
    window : Window
    flat : ndarray
        The window's flattened image (micro images of equal brightness), smoothed as for the centring.
    """

    xy: np.ndarray
    asymmetry: np.ndarray
    window: Window
    flat: np.ndarray


def plan_windows(shape, pitch: float, kind: str | None) -> list[Window]:
    """The whole image as one window, or a 5 × 5 layout of windows that together hold the lens budget."""
    h, w = shape
    pairs = len(symmetric_offsets(pitch)[0])
    cell = pitch * pitch * (math.sqrt(3.0) / 2.0 if kind == "hexagonal" else 1.0)
    if h * w / cell * pairs <= WHOLE_IMAGE_BUDGET:
        return [Window(0, h, 0, w, (0, h, 0, w))]
    budget_lenses = WINDOW_BUDGET / max(pairs, 1)
    n = WINDOWS_PER_SIDE
    side = max(math.sqrt(budget_lenses / (n * n) * cell), 6.0 * pitch)
    margin = int(math.ceil(3.0 * pitch)) + 2
    windows = []
    for fy in (np.arange(n) + 0.5) / n:
        for fx in (np.arange(n) + 0.5) / n:
            cy0 = int(max(0, round(fy * h - side / 2)))
            cx0 = int(max(0, round(fx * w - side / 2)))
            cy1, cx1 = int(min(h, cy0 + side)), int(min(w, cx0 + side))
            y0, x0 = max(0, cy0 - margin) & ~1, max(0, cx0 - margin) & ~1  # even: Bayer phase kept
            windows.append(Window(y0, min(h, cy1 + margin), x0, min(w, cx1 + margin), (cy0, cy1, cx0, cx1)))
    return windows


def measure_window(white: np.ndarray, cfa: str, window: Window, pitch: float, smoothing: float,
                   image_shape) -> Measured:
    """Steps 1, 3 and 4 in one window: candidates, then their sub-pixel point-symmetry centres.

    Candidates are kept in the window's core and at least half a pitch plus a pixel inside the image
    (their own cell on the sensor); symmetric sample pairs with a point off the image are left out.
    """
    from scipy import ndimage
    image = repair_outlier_pixels(mono_window(white, cfa, window.y0, window.y1, window.x0, window.x1))
    flattened = flatten(image, pitch)
    candidates = candidate_centres(flattened.flat, flattened.valid, pitch)
    h, w = image_shape
    cy0, cy1, cx0, cx1 = window.core
    gx, gy = candidates[:, 0] + window.x0, candidates[:, 1] + window.y0
    reach = 0.5 * pitch + 1.0
    keep = ((gx >= max(cx0, reach)) & (gx < min(cx1, w - 1 - reach))
            & (gy >= max(cy0, reach)) & (gy < min(cy1, h - 1 - reach)))
    sigma = max(smoothing * pitch, 0.7)
    smooth = ndimage.gaussian_filter(flattened.above_floor, sigma)
    xy, asym = refine_centres(smooth, candidates[keep], pitch, blur_variance=sigma * sigma + 1.0 / 12.0)
    xy = xy + np.array([window.x0, window.y0], dtype=np.float64)
    flat = ndimage.gaussian_filter(flattened.flat, sigma)
    return Measured(xy, asym, window, flat)
