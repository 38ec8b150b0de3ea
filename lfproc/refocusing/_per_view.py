"""Shift-and-sum with a per-view shift table: view (ky, kx) of slice a read at a·(σ_y, σ_x)[ky, kx].

Eq. 9 shifts view (ky, kx) by a·(c − ky, c − kx): separable, which the band kernels exploit. A
per-view table that is not separable — the sine condition's shifts of a high-NA microscope,
σ = g(ky, kx)·(c − k) (:func:`lfproc.geometry.refocus_slopes`) — is summed here view by view: each
view's shift is constant over the view, so it is resampled separably (x, then y) with the sampling
plans of the kernels (:func:`._plan.axis_plan` with ``factors``: the same positions, taps, weights and
"inside" rule), and the mean is taken per output pixel over the samples inside. With σ = (c − ky, c − kx)
the result equals the kernels' (tested). One numba kernel call per slice, slices on a thread pool.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from ._plan import axis_plan
from ._spline import postfilter


@numba.njit(cache=True, nogil=True)
def _slice_per_view(views, channels, s, marked, first_y, ntaps_y, w_y, lo_y, hi_y,
                    first_x, ntaps_x, w_x, lo_x, hi_x, out):
    """``out[py, px·C + ch]`` = mean over the marked views whose sample is inside, for one slice.

    Plans are per view v (flattened ky·m + kx) and phase r: ``first_*[v, r]``, ``ntaps_*[v, r]``,
    ``w_*[v, r, t]``, ``lo_*[v, r]``/``hi_*[v, r]`` (the outputs q of phase r that count).
    """
    n_views, ny, row_len = views.shape
    nx = row_len // channels
    py_len, px_len = out.shape[0], out.shape[1] // channels
    total = np.zeros((py_len, px_len * channels))
    count = np.zeros((py_len, px_len))
    xs = np.zeros((ny, px_len * channels))
    for v in range(n_views):
        if not marked[v]:
            continue
        xs[:] = 0.0
        for sy in range(ny):           # x-resample every source row of the view
            src = views[v, sy]
            dst = xs[sy]
            for r in range(s):
                for q in range(lo_x[v, r], hi_x[v, r] + 1):
                    o = (q * s + r) * channels
                    for t in range(ntaps_x[v, r]):
                        i = min(max(q + first_x[v, r] + t, 0), nx - 1) * channels
                        w = w_x[v, r, t]
                        for ch in range(channels):
                            dst[o + ch] += w * src[i + ch]
        for r in range(s):             # then y, into the slice's sums
            for q in range(lo_y[v, r], hi_y[v, r] + 1):
                p = q * s + r
                acc = total[p]
                for t in range(ntaps_y[v, r]):
                    row = xs[min(max(q + first_y[v, r] + t, 0), ny - 1)]
                    w = w_y[v, r, t]
                    for e in range(px_len * channels):
                        acc[e] += w * row[e]
                cnt = count[p]
                for rx in range(s):
                    for qx in range(lo_x[v, rx], hi_x[v, rx] + 1):
                        cnt[qx * s + rx] += 1.0
    for p in range(py_len):
        for px in range(px_len):
            n = count[p, px]
            for ch in range(channels):
                e = px * channels + ch
                out[p, e] = total[p, e] / n if n > 0 else 0.0


def refocus_per_view(views: np.ndarray, slopes, table, interpolation: str, upsample: int,
                     mask: np.ndarray | None = None, threads: int = 1) -> np.ndarray:
    """``(K, Ny', Nx', C)`` float32 slices of ``views`` (m, m, Ny, Nx, C) for the shift table ``(σ_y, σ_x)``.

    ``mask`` (m, m) keeps only the marked views (the mean runs over the marked samples inside).
    """
    sigma_y, sigma_x = (np.asarray(t, dtype=np.float64).ravel() for t in table)
    m, _, ny, nx, channels = views.shape
    flat = np.ascontiguousarray(views.reshape(m * m, ny, nx * channels))
    if flat.dtype not in (np.float32, np.float64):
        flat = flat.astype(np.float64)
    marked = np.ones(m * m, dtype=np.bool_) if mask is None else np.ascontiguousarray(np.asarray(mask, bool).ravel())
    s = upsample
    plan_y = axis_plan(slopes, m * m, ny, s, interpolation, sigma_y)
    plan_x = axis_plan(slopes, m * m, nx, s, interpolation, sigma_x)
    out = np.empty((len(slopes), (ny - 1) * s + 1, ((nx - 1) * s + 1) * channels), dtype=np.float32)

    def one(k):
        c = np.ascontiguousarray
        _slice_per_view(flat, channels, s, marked, c(plan_y.first[k]), c(plan_y.ntaps[k]), c(plan_y.weights[k]),
                        c(plan_y.lo[k]), c(plan_y.hi[k]), c(plan_x.first[k]), c(plan_x.ntaps[k]),
                        c(plan_x.weights[k]), c(plan_x.lo[k]), c(plan_x.hi[k]), out[k])

    if threads <= 1 or len(slopes) == 1:
        for k in range(len(slopes)):
            one(k)
    else:
        with ThreadPoolExecutor(max_workers=threads) as pool:
            list(pool.map(one, range(len(slopes))))
    out = out.reshape(len(slopes), (ny - 1) * s + 1, (nx - 1) * s + 1, channels)
    postfilter(out, plan_y.spline, plan_x.spline, s)      # cubic-spline only (a no-op otherwise)
    return out
