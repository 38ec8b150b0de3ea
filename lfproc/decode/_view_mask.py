"""Which views a decoder can deliver faithfully: the white-image probe behind the systematic refocus bias.

A decoded sample is ``K·capture / K·white`` for the sampling kernel K of that sample (the sensor pixel,
the demosaicing and the interpolation together, all linear for ``"fast"`` demosaicing). As a function
of the ray direction it reads, its *white-weighted centroid* is ``K·(white·x) / K·white``. The geometry
(and refocusing) assume that centroid is the view's nominal position, the lens centre plus
(k − c)·pitch/m̂. Where K reaches past the edge of the lens's own illuminated micro image that fails:

* dark pixels (outside the main lens aperture, the gaps between micro images) weigh nothing after the
  division by the white image, so the centroid moves *inwards*: the view behaves as one nearer the
  centre, its parallax is compressed, and a refocus sweep peaks at a lower a (focus too far);
* pixels of the neighbouring micro image are lit in the white image, so they are averaged in at full
  weight: crosstalk, whose centroid sits a whole lens away.

This probe measures that centroid per view at a sample of lenses away from the sensor border, by
decoding the white image multiplied by each pixel's offset from the centre of the lens whose cell
contains it. A view is delivered where the centroid is within ``tolerance`` effective pixels of
nominal at (nearly) every probed lens on which it is lit; the other views are set to 0 everywhere,
like views outside the aperture. Deciding per view (not per sample) keeps every slice evenly bright.
"""

from __future__ import annotations

import math

import numpy as np

from ..grid import LensGrid
from ._demosaic import to_channels
from ._positions import view_offsets_px
from ._resample import cv_flag

#: the most lenses probed (spread over the central 60 % of the grid)
PROBED_LENSES = 400
#: a view is delivered where its centroid is right at this fraction of the probed lenses it is lit on
REQUIRED_FRACTION = 0.9


def probe_lenses(grid: LensGrid, count: int = PROBED_LENSES) -> list[tuple[int, int]]:
    """Up to ``count`` lens indices spread over the central 60 % of the grid (whole grid if it is small)."""
    def spread(n):
        lo, hi = (int(0.2 * n), int(math.ceil(0.8 * n))) if n >= 10 else (0, n)
        per_axis = max(1, int(math.sqrt(count)))
        step = max(1, (hi - lo) // per_axis)
        return range(lo, hi, step)
    return [(r, q) for r in spread(grid.rows) for q in spread(grid.cols)]


def _foreign_pixels(grid: LensGrid, r: int, q: int, xx: np.ndarray, yy: np.ndarray) -> np.ndarray:
    """1.0 where a pixel centre is nearer another lens (among lens (r, q)'s neighbours) than (r, q), else 0."""
    lx, ly = grid.lens_xy(r, q)
    own = (xx - lx) ** 2 + (yy - ly) ** 2
    nearest_other = np.full(xx.shape, np.inf)
    for dr in range(-2, 3):
        for dq in range(-2, 3):
            if dr or dq:
                ox, oy = grid.lens_xy(r + dr, q + dq)
                np.minimum(nearest_other, (xx - ox) ** 2 + (yy - oy) ** 2, out=nearest_other)
    return (nearest_other < own).astype(np.float64)


def _read(image: np.ndarray, cfa: str, demosaic_method: str, map_x, map_y, flag) -> np.ndarray:
    """``image`` demosaiced and read at the maps: ``(m̂, m̂, C)``."""
    import cv2

    img = to_channels(image.astype(np.float32), cfa, demosaic_method)
    planes = [cv2.remap(np.ascontiguousarray(img[..., ch0:ch0 + 4] if img.shape[2] > 1 else img[..., 0]),
                        map_x, map_y, flag, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
              for ch0 in range(0, img.shape[2], 4)]
    return np.concatenate([p.reshape(map_x.shape + (-1,)) for p in planes], axis=-1)


def centroid_errors(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str, demosaic_method: str,
                    interpolation: str, lenses=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per probed lens and view (worst channel): the centroid shift (px), the crosstalk fraction, the white.

    The shift is the distance between the white-weighted centroid of a sample's kernel and the
    kernel's own (unweighted) centroid; the crosstalk fraction is the share of the sample's white
    that comes from pixels of other lenses' cells. Returns three ``(lenses, m̂, m̂)`` arrays; the first
    two are NaN where the white reads 0.
    """
    flag = cv_flag(interpolation)
    off_x, off_y = view_offsets_px(grid, m_hat)
    h, w = white.shape[:2]
    half = int(math.ceil(grid.pitch_px)) + 6
    shifts, crosstalk, levels = [], [], []
    for r, q in (lenses if lenses is not None else probe_lenses(grid)):
        cx, cy = (float(v) for v in grid.lens_xy(r, q))
        x0, y0 = max(0, int(cx) - half) & ~1, max(0, int(cy) - half) & ~1   # even: the CFA phase stays
        x1, y1 = min(w, int(cx) + half + 1), min(h, int(cy) + half + 1)
        if x1 <= x0 or y1 <= y0:
            continue
        patch = np.asarray(white[y0:y1, x0:x1], dtype=np.float64)
        yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float64)
        dx, dy, foreign = xx - cx, yy - cy, _foreign_pixels(grid, r, q, xx, yy)
        if patch.ndim == 3:
            dx, dy, foreign = dx[..., None], dy[..., None], foreign[..., None]
        flat = np.ones_like(patch)
        map_x = (cx + off_x - x0).astype(np.float32)
        map_y = (cy + off_y - y0).astype(np.float32)
        level, wx, wy, wf, ones, gx, gy = (_read(p, cfa, demosaic_method, map_x, map_y, flag) for p in
                                           (patch, patch * dx, patch * dy, patch * foreign, flat, flat * dx,
                                            flat * dy))
        with np.errstate(invalid="ignore", divide="ignore"):
            shift = np.hypot(wx / level - gx / ones, wy / level - gy / ones)
            share = np.abs(wf / level)
        dark = ~(level > 0)
        shift[dark] = np.nan
        share[dark] = np.nan
        shifts.append(np.max(shift, axis=-1))
        crosstalk.append(np.max(share, axis=-1))
        levels.append(np.min(level, axis=-1))
    if not shifts:
        empty = np.full((0, m_hat, m_hat), np.nan)
        return empty, empty, np.zeros((0, m_hat, m_hat))
    return np.array(shifts), np.array(crosstalk), np.array(levels)


def faithful_views(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str, demosaic_method: str,
                   interpolation: str, dark_fraction: float, tolerance: float,
                   crosstalk_tolerance: float) -> np.ndarray:
    """Boolean ``(m̂, m̂)``: the views the decoder delivers (see the module docstring).

    A view is kept where, among the probed lenses on which its white sample is lit (above
    ``dark_fraction`` of the bright level), at least :data:`REQUIRED_FRACTION` have the centroid within
    ``tolerance`` effective pixels (pitch/m̂) of the kernel's own and at most ``crosstalk_tolerance`` of
    their white from other lenses (a view lit on none of them, outside the aperture, is not delivered).
    """
    errors, crosstalk, levels = centroid_errors(white, grid, m_hat, cfa, demosaic_method, interpolation)
    if errors.shape[0] == 0:
        return np.ones((m_hat, m_hat), dtype=bool)
    bright = float(np.percentile(levels, 99))
    lit = levels > dark_fraction * bright if bright > 0 else np.zeros(levels.shape, dtype=bool)
    right = (lit & (np.nan_to_num(errors, nan=np.inf) <= tolerance * grid.pitch_px / m_hat)
             & (np.nan_to_num(crosstalk, nan=np.inf) <= crosstalk_tolerance))
    n_lit = lit.sum(axis=0)
    return right.sum(axis=0) >= REQUIRED_FRACTION * np.maximum(n_lit, 1)
