"""Where the lit disc of the micro images is: its centre off the grid's lens centres, from its edge.

A white image lights, behind every lens, the disc that the main lens's aperture (a microscope
objective's NA) projects through it. The decoder reads the views around the grid's lens centres; when
the disc sits off them (a tilted illumination, an objective pupil off the axis, an exit pupil off the
lattice's centre) the views inside the aperture are an off-centre set, and the centred, symmetric set
the geometry assumes has to be read around the disc's own centre (:mod:`._view_mask`).

Measuring that centre from the white-weighted centroid of the raw pixels is biased twice over:

* on a Bayer mosaic the channels have different gains, and the pixels of one channel are not placed
  symmetrically about a lens centre: the centroid leans towards the brighter channel's pixels;
* a disc wider than the lens's cell is cut by the cell's border (the neighbour's light is not this
  lens's), and the centroid of a cut disc leans towards the cell's centre.

This module fits the disc's *edge* instead. Every probed lens contributes the pixels of its own cell
(nearest lens centre, :func:`._cells.nearest_lens`), each Bayer phase (or channel) normalised by its own
lit level in that lens, so gains cancel; pixels at the cell's border are left out, so a cut disc is
fitted on the edge it shows. All lenses are pooled around their own centres, whose sub-pixel phases
differ, so the pooled profile samples the edge finely. The model is a disc of radius R at offset
(x₀, y₀), its edge blurred by σ: level(ρ) = ½·erfc((ρ − R)/(√2·σ)), ρ = |(dx − x₀, dy − y₀)|, fitted
by least squares (:func:`scipy.optimize.least_squares`), with the offset's standard error from the fit.

A disc that fills its cell shows no edge: its centre is not measurable and is taken as the grid's
(``measured`` false): a lens grid fitted to such a white image is centred on its micro images anyway.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..grid import LensGrid
from ._cells import nearest_lens

#: a lens-phase's pixels count as lit above this fraction of its brightest pixel (its level: their median)
LIT_LEVEL = 0.5
#: the disc shows an edge when at least this share of the pooled interior pixels is dark (below half level)
MIN_DARK_SHARE = 0.03
#: at least this many pooled pixels for a fit
MIN_PIXELS = 50


@dataclass(frozen=True)
class DiscCentre:
    """The lit disc's centre off the lens centres: ``offset_px`` (x, y) sensor pixels, its standard error
    ``sigma_px``, the fitted ``radius_px`` and edge blur ``blur_px``; ``measured`` false where the disc
    shows no edge (fills its cell: offset 0), ``lenses`` the lenses pooled."""

    offset_px: tuple
    sigma_px: float
    radius_px: float
    blur_px: float
    measured: bool
    lenses: int


def _phases(image: np.ndarray, cfa: str):
    """(row offset, col offset, channel) of each plane measured on its own: the four Bayer phases of a mosaic,
    each channel of an (H, W, C) image, or the mono image."""
    if image.ndim == 2:
        return [(py, px, None) for py in (0, 1) for px in (0, 1)] if cfa != "none" else [(0, 0, None)]
    return [(0, 0, ch) for ch in range(image.shape[2])]


def _lens_pixels(image, grid, cfa, r, q):
    """Pooled ``(dx, dy, level)`` of lens (r, q): its own cell's pixels off the cell border, each phase
    normalised by its lit level in this lens; ``None`` where the cell leaves the sensor or is dark."""
    h, w = image.shape[:2]
    cx, cy = (float(v) for v in grid.lens_xy(r, q))
    half = int(math.ceil(0.75 * grid.pitch_px)) + 2
    x0, y0 = (int(math.floor(cx)) - half) & ~1, (int(math.floor(cy)) - half) & ~1   # even: CFA phase kept
    size = 2 * half + 2
    if x0 < 1 or y0 < 1 or x0 + size + 1 > w or y0 + size + 1 > h:
        return None
    yy, xx = np.mgrid[y0 - 1:y0 + size + 1, x0 - 1:x0 + size + 1].astype(np.float64)
    nr, nq = nearest_lens(grid, xx, yy)
    own = (nr == r) & (nq == q)
    inner = own[1:-1, 1:-1].copy()
    for sy in (0, 1, 2):            # off the border: all eight neighbours in the same cell
        for sx in (0, 1, 2):
            inner &= own[sy:sy + size, sx:sx + size]
    dx, dy = xx[1:-1, 1:-1] - cx, yy[1:-1, 1:-1] - cy
    patch = image[y0:y0 + size, x0:x0 + size]
    out = []
    for py, px, ch in _phases(image, cfa):
        sel = (slice(py, None, 2), slice(px, None, 2)) if ch is None and cfa != "none" else (slice(None),) * 2
        values = (patch[sel] if ch is None else patch[..., ch][sel]).astype(np.float64)
        keep = inner[sel]
        v = values[keep]
        if v.size == 0 or not np.isfinite(v).all():
            return None
        top = float(v.max())
        lit = v[v > LIT_LEVEL * top]
        level = float(np.median(lit)) if lit.size else 0.0
        if not level > 0:
            return None
        out.append(np.stack([dx[sel][keep], dy[sel][keep], v / level], axis=-1))
    return np.concatenate(out, axis=0)


def measure_disc_centre(white: np.ndarray, grid: LensGrid, cfa: str, lenses) -> DiscCentre:
    """The lit disc's centre off the lens centres of ``lenses`` ((r, q) pairs), fitted to its edge (module
    docstring). Pure function of the white image (linear, dark frame subtracted) and the grid."""
    from scipy.optimize import least_squares
    from scipy.special import erfc

    white = np.asarray(white)
    pooled = [p for p in (_lens_pixels(white, grid, cfa, r, q) for r, q in lenses) if p is not None]
    none = DiscCentre((0.0, 0.0), 0.0, 0.0, 0.0, False, len(pooled))
    if not pooled:
        return none
    data = np.concatenate(pooled, axis=0)
    dx, dy, level = data.T
    if data.shape[0] < MIN_PIXELS or np.mean(level < 0.5) < MIN_DARK_SHARE:
        return none
    lit = level >= 0.5
    start_x, start_y = float(np.mean(dx[lit])), float(np.mean(dy[lit]))
    start_r = math.sqrt(np.mean(lit) * np.mean(np.hypot(dx, dy) ** 2) * 2.0)   # area share of the pooled cell

    def residual(p):
        rho = np.hypot(dx - p[0], dy - p[1])
        return 0.5 * erfc((rho - p[2]) / (math.sqrt(2.0) * p[3])) - level

    fit = least_squares(residual, [start_x, start_y, max(start_r, 1.0), 0.7],
                        bounds=([-grid.pitch_px, -grid.pitch_px, 0.5, 0.2],
                                [grid.pitch_px, grid.pitch_px, 2.0 * grid.pitch_px, grid.pitch_px]))
    dof = max(1, data.shape[0] - 4)
    s2 = float(np.sum(fit.fun ** 2)) / dof
    try:
        cov = np.linalg.inv(fit.jac.T @ fit.jac) * s2
        sigma = float(math.sqrt(max(cov[0, 0], 0.0) + max(cov[1, 1], 0.0)))
    except np.linalg.LinAlgError:
        sigma = math.inf
    x, y, radius, blur = (float(v) for v in fit.x)
    return DiscCentre((x, y), sigma, radius, blur, True, len(pooled))
