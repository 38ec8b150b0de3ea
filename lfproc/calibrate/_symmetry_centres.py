"""Step 4 of calibration: sub-pixel micro image centres as points of best point symmetry.

Each centre moves (Gauss–Newton, all lenses at once) to the point about which its neighbourhood is most
point-symmetric, allowing for a linear brightness slope across the micro image (vignetting):
``Σ m(d)·[S(c+d) − S(c−d) − (g·d)(S(c+d) + S(c−d))]² → min`` over c and g. Thin disks, disks clipped to
their cell and blurred spots are all centred without bias; what asymmetry remains flags micro images cut
by mechanical vignetting, noise or the image border.
"""

from __future__ import annotations

import math

import numpy as np


def symmetric_offsets(pitch: float, radius: float = 0.8, full: float = 0.62,
                      max_per_axis: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """Half-plane offsets d (K, 2) within ``radius``·pitch and their weights m(|d|).

    The weight is 1 up to ``full``·pitch and falls as cos² to 0 at ``radius``·pitch (the corners of a
    cell, where fat micro images leave their only gaps, lie at 0.58–0.71 pitch). The spacing is 1 px or
    coarser, so at most about 2·max_per_axis² pairs are used whatever the pitch.
    """
    r_max = radius * pitch
    step = max(1.0, r_max / max_per_axis)
    n = int(math.floor(r_max / step))
    g = np.arange(-n, n + 1) * step
    dx, dy = np.meshgrid(g, g)
    dist = np.hypot(dx, dy)
    keep = (dist <= r_max) & ((dy > 0) | ((dy == 0) & (dx > 0)))
    rel = (dist[keep] - full * pitch) / ((radius - full) * pitch)
    weight = np.where(rel <= 0, 1.0, np.cos(0.5 * math.pi * np.clip(rel, 0.0, 1.0)) ** 2)
    return np.stack([dx[keep], dy[keep]], -1), weight


def refine_centres(smooth: np.ndarray, xy: np.ndarray, pitch: float, blur_variance: float = 0.0,
                   iterations: int = 12, max_shift: float | None = None,
                   offsets: tuple[np.ndarray, np.ndarray] | None = None,
                   chunk_samples: int = 4_000_000) -> tuple[np.ndarray, np.ndarray]:
    """Move each centre to the point of best point symmetry of ``smooth`` (Gauss–Newton, vectorised).

    A micro image P that is point-symmetric about c but lies under a brightness slope g (vignetting)
    satisfies ``S(c + d) − S(c − d) = (g·d)·(S(c + d) + S(c − d))``. For every lens at once this solves

        min over c, g of  Σ_k m_k [S(c + d_k) − S(c − d_k) − (g·d_k)(S(c + d_k) + S(c − d_k))]²,

    so a linear slope across the micro image does not move its centre. Smoothing (variance
    ``blur_variance``: σ² of the Gaussian plus 1/12 for the pixel's area) turns a sloped micro image into a
    symmetric one displaced by −σ²·g, because G∗(x·P) = x·(G∗P) + σ²·∇(G∗P); that displacement is added
    back. ``S`` is sampled with cubic splines, its gradient bilinearly; a pair (c + d, c − d) with either
    point off the image is left out as a pair.

    Returns
    -------
    xy : ndarray (N, 2)
        The centres.
    asymmetry : ndarray (N,)
        ``Σ m r² / Σ m (S(c+d)² + S(c−d)²)`` at the solution: about 0 for a symmetric micro image, of order
        1 for half a disk; ``inf`` where a centre moved more than ``max_shift`` (default a quarter pitch)
        from its start, towards another point of symmetry of the lattice such as the midpoint of two lenses.
    """
    from scipy import ndimage
    d, m = offsets if offsets is not None else symmetric_offsets(pitch)
    coeffs = ndimage.spline_filter(smooth, order=3, mode="mirror")
    gradients = np.gradient(smooth)[::-1]  # (d/dx, d/dy)
    start_xy = np.array(xy, dtype=np.float64).reshape(-1, 2)
    out = start_xy.copy()
    asym = np.full(len(out), np.inf)
    max_step = 0.1 * pitch
    max_shift = 0.25 * pitch if max_shift is None else max_shift
    max_slope = 0.5 / float(np.max(np.hypot(d[:, 0], d[:, 1]))) if len(d) else 0.0
    per_chunk = max(1, chunk_samples // max(len(d), 1))
    for first in range(0, len(out), per_chunk):
        c = out[first:first + per_chunk].copy()
        g = np.zeros_like(c)
        active = np.arange(len(c))  # lenses still moving: converged ones are not evaluated again
        for _ in range(iterations):
            if active.size == 0:
                break
            r, jac, w, _ = _symmetry_terms(coeffs, gradients, c[active], g[active], d, m)
            normal = np.einsum("nk,nki,nkj->nij", w, jac, jac)
            rhs = np.einsum("nk,nki,nk->ni", w, jac, r)
            trace = np.trace(normal, axis1=1, axis2=2)
            blank = ~(trace > 0)  # no texture at all (or off the image): the lens stays where it is
            normal[blank] = np.eye(4)
            rhs[blank] = 0.0
            normal += (1e-9 * np.where(blank, 1.0, trace))[:, None, None] * np.eye(4)
            delta = -_solve_batched(normal, rhs)
            step = delta[:, :2]
            norm = np.hypot(step[:, 0], step[:, 1])
            step *= np.minimum(1.0, max_step / np.maximum(norm, 1e-300))[:, None]
            c[active] += step
            g[active] = np.clip(g[active] + delta[:, 2:], -max_slope, max_slope)
            active = active[np.max(np.abs(step), axis=1) >= 1e-4]  # Gauss–Newton: what is left is far smaller
        r, _, w, energy = _symmetry_terms(coeffs, None, c, g, d, m)
        with np.errstate(divide="ignore", invalid="ignore"):
            asym[first:first + per_chunk] = np.where(energy > 0, (w * r * r).sum(1) / energy, np.inf)
        out[first:first + per_chunk] = c + blur_variance * g
    moved = np.hypot(*(out - start_xy).T)
    asym[~(moved <= max_shift)] = np.inf
    return out, asym


def _solve_batched(normal: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve the stacked normal equations; a degenerate system gives a zero step."""
    try:
        delta = np.linalg.solve(normal, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        delta = np.einsum("nij,nj->ni", np.linalg.pinv(normal), rhs)
    delta[~np.isfinite(delta).all(1)] = 0.0
    return delta


def _symmetry_terms(coeffs, gradients, c, g, d, m):
    """Residuals of the symmetry model, Jacobian in (cx, cy, gx, gy) (if ``gradients``), weights, energy."""
    h, w = coeffs.shape
    plus, minus = c[:, None, :] + d, c[:, None, :] - d
    on_image = ((plus[..., 0] >= 0) & (plus[..., 0] <= w - 1) & (plus[..., 1] >= 0) & (plus[..., 1] <= h - 1)
                & (minus[..., 0] >= 0) & (minus[..., 0] <= w - 1) & (minus[..., 1] >= 0) & (minus[..., 1] <= h - 1))
    weight = m * on_image
    s_plus, s_minus = _sample(coeffs, plus, order=3), _sample(coeffs, minus, order=3)
    slope = g[:, None, 0] * d[:, 0] + g[:, None, 1] * d[:, 1]  # g·d, shape (n, K)
    total = s_plus + s_minus
    residual = s_plus - s_minus - slope * total
    energy = (weight * (s_plus ** 2 + s_minus ** 2)).sum(1)
    jac = None
    if gradients is not None:
        jac = np.empty(residual.shape + (4,))
        for axis, grad in enumerate(gradients):
            g_plus, g_minus = _sample(grad, plus, order=1), _sample(grad, minus, order=1)
            jac[..., axis] = g_plus - g_minus - slope * (g_plus + g_minus)
            jac[..., 2 + axis] = -d[:, axis] * total
    return residual, jac, weight, energy


def _sample(image: np.ndarray, xy: np.ndarray, order: int) -> np.ndarray:
    """``image`` at points (…, 2) given as (x, y); order 3 expects spline coefficients."""
    from scipy import ndimage
    coords = np.stack([xy[..., 1].reshape(-1), xy[..., 0].reshape(-1)])
    out = ndimage.map_coordinates(image, coords, order=order, mode="mirror", prefilter=False)
    return out.reshape(xy.shape[:-1])


