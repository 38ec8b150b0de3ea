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
(x₀, y₀), its edge blurred over a width s: level(ρ) = 1/(1 + exp((ρ − R)/s)), ρ = |(dx − x₀, dy − y₀)|
(any edge profile symmetric about R leaves the centre unbiased), fitted by least squares
(Levenberg–Marquardt with the analytic Jacobian, numpy only: importing scipy.optimize alone took
longer than the fit), with the offset's standard error from the fit.

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


def _model(p, dx, dy):
    """The blurred disc at ``p`` = (x₀, y₀, R, s): levels and their Jacobian ``(N, 4)``."""
    ex, ey = dx - p[0], dy - p[1]
    rho = np.maximum(np.hypot(ex, ey), 1e-9)
    f = 1.0 / (1.0 + np.exp(np.clip((rho - p[2]) / p[3], -60.0, 60.0)))
    slope = f * (1.0 - f) / p[3]
    jac = np.stack([slope * ex / rho, slope * ey / rho, slope, slope * (rho - p[2]) / p[3]], axis=-1)
    return f, jac


def _fit(p, dx, dy, level, low, high, iterations: int = 60):
    """Levenberg–Marquardt for :func:`_model` within the bounds ``low``, ``high``: (parameters, residuals,
    Jacobian)."""
    p = np.clip(np.asarray(p, dtype=np.float64), low, high)
    f, jac = _model(p, dx, dy)
    r = f - level
    cost, damping = float(r @ r), 1e-3
    for _ in range(iterations):
        normal = jac.T @ jac
        step = np.linalg.solve(normal + damping * np.diag(np.diag(normal) + 1e-12), -(jac.T @ r))
        trial = np.clip(p + step, low, high)
        f_t, jac_t = _model(trial, dx, dy)
        r_t = f_t - level
        cost_t = float(r_t @ r_t)
        if cost_t < cost:
            converged = cost - cost_t < 1e-12 * max(cost, 1e-30) and np.max(np.abs(trial - p)) < 1e-7
            p, r, jac, cost, damping = trial, r_t, jac_t, cost_t, max(damping / 3.0, 1e-9)
            if converged:
                break
        else:
            damping *= 4.0
            if damping > 1e9:
                break
    return p, r, jac


def measure_disc_centre(white: np.ndarray, grid: LensGrid, cfa: str, lenses) -> DiscCentre:
    """The lit disc's centre off the lens centres of ``lenses`` ((r, q) pairs), fitted to its edge (module
    docstring). Pure function of the white image (linear, dark frame subtracted) and the grid."""
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
    start = [float(np.mean(dx[lit])), float(np.mean(dy[lit])),
             max(1.0, math.sqrt(np.mean(lit) * np.mean(np.hypot(dx, dy) ** 2) * 2.0)),   # the lit share's radius
             0.4]
    low = np.array([-grid.pitch_px, -grid.pitch_px, 0.5, 0.05])
    high = np.array([grid.pitch_px, grid.pitch_px, 2.0 * grid.pitch_px, grid.pitch_px])
    p, r, jac = _fit(start, dx, dy, level, low, high)
    s2 = float(r @ r) / max(1, data.shape[0] - 4)
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
        sigma = float(math.sqrt(max(cov[0, 0], 0.0) + max(cov[1, 1], 0.0)))
    except np.linalg.LinAlgError:
        sigma = math.inf
    x, y, radius, blur = (float(v) for v in p)
    return DiscCentre((x, y), sigma, radius, blur, True, len(pooled))
