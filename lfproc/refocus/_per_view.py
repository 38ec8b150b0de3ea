"""Shift-and-sum with a per-view shift table: view (ky, kx) of slice a read at a·(σ_y, σ_x)[ky, kx].

Eq. 9 shifts view (ky, kx) by a·(c − ky, c − kx): separable, which the band kernels exploit. A
per-view table that is not separable — the sine condition's shifts of a high-NA microscope,
σ = g(ky, kx)·(c − k) (:func:`lfproc.geometry.refocus_slopes`) — is summed here view by view, each
view resampled separably with the same sampling plans (positions, taps, weights, "inside" rule) as the
kernels (:func:`._plan.axis_plan` with ``factors``), and the mean taken over the samples inside, per
output pixel. With σ = (c − ky, c − kx) the result equals the kernels' (tested).
"""

from __future__ import annotations

import numpy as np

from ._plan import axis_plan

#: slices resampled together per view (bounds the gathered temporaries)
SLICE_CHUNK = 16


def _taps(plan, n: int, s: int):
    """(indices (K, P, 4), weights (K, P, 4), inside (K, P)) of a one-view plan; weights 0 outside."""
    p = np.arange((n - 1) * s + 1)
    q, r = p // s, p % s
    first, ntaps = plan.first[:, 0, r], plan.ntaps[:, 0, r]
    t = np.arange(4)
    idx = np.clip(q[None, :, None] + first[..., None] + t, 0, n - 1)
    inside = (plan.lo[:, 0, r] <= q) & (q <= plan.hi[:, 0, r])
    weights = np.where((t < ntaps[..., None]) & inside[..., None], plan.weights[:, 0, r, :], 0.0)
    return idx, weights, inside


def refocus_per_view(views: np.ndarray, slopes, table, interpolation: str, upsample: int,
                     mask: np.ndarray | None = None) -> np.ndarray:
    """``(K, Ny', Nx', C)`` float32 slices of ``views`` (m, m, Ny, Nx, C) for the shift table ``(σ_y, σ_x)``.

    ``mask`` (m, m) keeps only the marked views (the mean runs over the marked samples inside).
    """
    sigma_y, sigma_x = (np.asarray(t, dtype=np.float64) for t in table)
    m, _, ny, nx, channels = views.shape
    a = np.asarray(slopes, dtype=np.float64)
    s = upsample
    py, px = (ny - 1) * s + 1, (nx - 1) * s + 1
    total = np.zeros((len(a), py, px, channels))
    count = np.zeros((len(a), py, px))
    for ky in range(m):
        for kx in range(m):
            if mask is not None and not mask[ky, kx]:
                continue
            view = views[ky, kx].astype(np.float64, copy=False)
            for k0 in range(0, len(a), SLICE_CHUNK):
                part = a[k0:k0 + SLICE_CHUNK]
                iy, wy, in_y = _taps(axis_plan(part, 1, ny, s, interpolation, [sigma_y[ky, kx]]), ny, s)
                ix, wx, in_x = _taps(axis_plan(part, 1, nx, s, interpolation, [sigma_x[ky, kx]]), nx, s)
                rows = np.einsum("kpt,kptxc->kpxc", wy, view[iy])                      # (k, Py, Nx, C)
                gathered = rows[np.arange(len(part))[:, None, None], :, ix]              # (k, Px, 4, Py, C)
                total[k0:k0 + len(part)] += np.einsum("kqt,kqtpc->kpqc", wx, gathered)
                count[k0:k0 + len(part)] += in_y[:, :, None] & in_x[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(count[..., None] > 0, total / count[..., None], 0.0)
    return out.astype(np.float32)
