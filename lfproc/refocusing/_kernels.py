"""The numba kernels of shift-and-sum refocusing (Eq. 9): one band of output rows per call, GIL released.

See the package docstring for the data layout and the precision rules they implement.
"""

from __future__ import annotations

import numba
import numpy as np

# ----------------------------------------------------------------------------- numba kernels
# Compiled lazily on first call (no signatures given) and cached on disk (cache=True), once per input
# dtype; numba is imported with this module, which ``import lfproc`` does not import. ``views`` arrive
# as (m, m, Ny, Nx·C): each (ky, kx, row) is one contiguous segment of Nx·C values, and the shift of a
# view is constant along a row, so every inner loop runs over contiguous slices (slices, not offset
# indices, so that LLVM sees non-negative indices and vectorises).
# Per band of output rows and view row ky, the m̂ views of that view row are summed, shifted, into
# per-view-row partial sums, which then go into the float64 accumulators of the slices (the band is
# sized to keep both in L2/L3). A source row is fetched from memory once per band and used by every
# slice that reads it; neighbouring bands re-read only the rows that their slices' shifts share.

@numba.njit(cache=True, nogil=True)
def _normalise(acc, count_y, count_x, channels, row0, out):
    """``out[k, row0 + i] = acc[k, i] / (count_y · count_x)``: the mean of Eq. 9 over the samples inside."""
    n_slices, n_rows, row_len = acc.shape
    cols = row_len // channels
    for k in range(n_slices):
        for i in range(n_rows):
            cy = count_y[k, row0 + i]
            for jx in range(cols):
                scale = 1.0 / (cy * count_x[k, jx])
                for ch in range(channels):
                    e = jx * channels + ch
                    out[k, row0 + i, e] = acc[k, i, e] * scale


@numba.njit(cache=True, nogil=True)
def _add_into(acc_row, part):
    for i in range(acc_row.shape[0]):
        acc_row[i] += part[i]


@numba.njit(cache=True, nogil=True)
def _add_weighted(acc_row, part, w):
    """``acc_row += w · part`` (a plain add for unit weights: whole-lens y-taps multiply nothing)."""
    if w == 1.0:
        _add_into(acc_row, part)
    else:
        for i in range(acc_row.shape[0]):
            acc_row[i] += w * part[i]


@numba.njit(cache=True, nogil=True)
def _source_rows(ky, row0, row1, first_y, ntaps_y, lo_y, hi_y, src_rows, need_lo, need_hi):
    """The source rows that slice k reads for the output rows ``row0 … row1 − 1`` of view row ky, clamped
    to the array, into ``need_lo[k] … need_hi[k]`` (``need_lo > need_hi``: none); returns their union
    ``(sy_lo, sy_hi)`` (``sy_lo > sy_hi``: none) — the rows of the view row that the band streams through."""
    sy_lo = src_rows
    sy_hi = -1
    for k in range(first_y.shape[0]):
        j0 = max(row0, lo_y[k, ky])
        j1 = min(row1 - 1, hi_y[k, ky])
        if j0 > j1:
            need_lo[k] = src_rows
            need_hi[k] = -1
            continue
        need_lo[k] = min(max(j0 + first_y[k, ky], 0), src_rows - 1)
        need_hi[k] = min(max(j1 + first_y[k, ky] + ntaps_y[k, ky] - 1, 0), src_rows - 1)
        sy_lo = min(sy_lo, need_lo[k])
        sy_hi = max(sy_hi, need_hi[k])
    return sy_lo, sy_hi


@numba.njit(cache=True, nogil=True)
def _gather_band(views, channels, first_y, ntaps_y, lo_y, hi_y, first_x, lo_x, hi_x, count_y, count_x,
                 row0, row1, part_kind, out):
    """Output rows ``row0 … row1 − 1`` of every slice for whole-lens shifts (integer ``a``, or nearest, at
    ``upsample = 1``): pure adds of shifted row segments, no weights.

    ``first_*[k, v]`` is the shift of view index v for slice k (``ntaps_y`` all 1); ``lo_*``/``hi_*`` the
    output range that reads inside the view. Loop order: view row ky, view column kx, source row sy, slice k — each view
    is read as one contiguous stream of the band's rows (what hardware prefetchers do best), each row
    once for all the slices that use it, into per-view-row partial sums ``part`` that then go into the
    float64 accumulators.
    """
    m = views.shape[0]
    src_rows = views.shape[2]
    n_slices, _, row_len = out.shape
    acc = np.zeros((n_slices, row1 - row0, row_len))
    part = np.empty((n_slices, row1 - row0, row_len), dtype=part_kind.dtype)
    need_lo = np.empty(n_slices, dtype=np.int64)
    need_hi = np.empty(n_slices, dtype=np.int64)
    for ky in range(m):
        sy_lo, sy_hi = _source_rows(ky, row0, row1, first_y, ntaps_y, lo_y, hi_y, src_rows, need_lo, need_hi)
        part[:] = 0
        for kx in range(views.shape[1]):
            for sy in range(sy_lo, sy_hi + 1):
                for k in range(n_slices):
                    jy = sy - first_y[k, ky]
                    if jy < row0 or jy >= row1 or jy < lo_y[k, ky] or jy > hi_y[k, ky]:
                        continue
                    if lo_x[k, kx] > hi_x[k, kx]:
                        continue
                    e0 = lo_x[k, kx] * channels
                    e1 = (hi_x[k, kx] + 1) * channels
                    off = first_x[k, kx] * channels
                    dst = part[k, jy - row0, e0:e1]
                    src = views[ky, kx, sy, e0 + off:e1 + off]
                    for i in range(dst.shape[0]):
                        dst[i] += src[i]
        for k in range(n_slices):
            for jy in range(max(row0, lo_y[k, ky]), min(row1 - 1, hi_y[k, ky]) + 1):
                _add_into(acc[k, jy - row0], part[k, jy - row0])
    _normalise(acc, count_y, count_x, channels, row0, out)


@numba.njit(cache=True, nogil=True)
def _add_taps_clamped(dst, src, channels, s, r, n, first, ntaps, w, q_from, q_to):
    """Outputs ``q_from … q_to`` of phase r, taps with source indices clamped to ``[0, n − 1]`` (cubic edges)."""
    for q in range(q_from, q_to + 1):
        o = (q * s + r) * channels
        for t in range(ntaps):
            i = min(max(q + first + t, 0), n - 1) * channels
            for ch in range(channels):
                dst[o + ch] += w[t] * src[i + ch]


@numba.njit(cache=True, nogil=True)
def _add_taps_strided(dst, src, channels, s, r, first, ntaps, w, q_from, q_to):
    """Outputs ``q_from … q_to`` of phase r of an upsampled row (stride ``s`` pixels), all taps inside."""
    for q in range(q_from, q_to + 1):
        o = (q * s + r) * channels
        i = (q + first) * channels
        for ch in range(channels):
            value = w[0] * src[i + ch]
            for t in range(1, ntaps):
                value += w[t] * src[i + t * channels + ch]
            dst[o + ch] += value


@numba.njit(cache=True, nogil=True)
def _add_row(dst, src, channels, s, n, first, ntaps, w, lo, hi):
    """Add one source row of one view, resampled along x at every phase r of the output grid, to ``dst``.

    ``first``, ``ntaps``, ``lo``, ``hi`` (per phase) and ``w`` (phase × tap) are that view's x plan.
    """
    for r in range(s):
        q0 = lo[r]
        q1 = hi[r]
        if q0 > q1:
            continue
        f = first[r]
        nt = ntaps[r]
        # outputs whose taps q + f … q + f + nt − 1 all lie inside [0, n − 1]; only cubic has others
        qa = max(q0, -f)
        qb = min(q1, n - nt - f)
        if qa > qb:
            _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], q0, q1)
            continue
        _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], q0, qa - 1)
        _add_taps_clamped(dst, src, channels, s, r, n, f, nt, w[r], qb + 1, q1)
        if s != 1:
            _add_taps_strided(dst, src, channels, s, r, f, nt, w[r], qa, qb)
            continue
        e0 = qa * channels
        e1 = (qb + 1) * channels
        off = f * channels
        d = dst[e0:e1]
        s0 = src[e0 + off:e1 + off]
        w0 = w[r, 0]
        if nt == 1:
            if w0 == 1.0:
                for i in range(d.shape[0]):
                    d[i] += s0[i]
            else:
                for i in range(d.shape[0]):
                    d[i] += w0 * s0[i]
        elif nt == 2:
            s1 = src[e0 + off + channels:e1 + off + channels]
            w1 = w[r, 1]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i]
        else:
            s1 = src[e0 + off + channels:e1 + off + channels]
            s2 = src[e0 + off + 2 * channels:e1 + off + 2 * channels]
            s3 = src[e0 + off + 3 * channels:e1 + off + 3 * channels]
            w1 = w[r, 1]
            w2 = w[r, 2]
            w3 = w[r, 3]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i] + w2 * s2[i] + w3 * s3[i]


@numba.njit(cache=True, nogil=True)
def _interpolated_band(views, channels, s, first_y, ntaps_y, w_y, lo_y, hi_y,
                       first_x, ntaps_x, w_x, lo_x, hi_x, count_y, count_x, row0, row1, part_kind, out):
    """Output rows ``row0 … row1 − 1`` of every slice in the general case: fractional positions and/or
    upsampling, separable taps (see :class:`AxisPlan`).

    Separable: for a view row ky and slice k every view of the row reads the same source row, so the
    x-resampled sum over kx of source row sy is formed once and kept in a ring of four rows (the rows an
    output row needs are at most four consecutive ones, and they only move forward with the output
    row); each output row then adds its y-taps' weighted rows from the ring.
    """
    m = views.shape[0]
    src_rows = views.shape[2]
    src_cols = views.shape[3] // channels
    n_slices, _, row_len = out.shape
    acc = np.zeros((n_slices, row1 - row0, row_len))
    ring = np.empty((n_slices, 4, row_len), dtype=part_kind.dtype)
    ring_row = np.empty((n_slices, 4), dtype=np.int64)
    for ky in range(m):
        ring_row[:] = -1
        for py in range(row0, row1):
            q = py // s
            r = py - q * s
            for k in range(n_slices):
                if q < lo_y[k, ky, r] or q > hi_y[k, ky, r]:
                    continue
                dst = acc[k, py - row0]
                for t in range(ntaps_y[k, ky, r]):
                    sy = min(max(q + first_y[k, ky, r] + t, 0), src_rows - 1)
                    slot = sy % 4
                    x_sum = ring[k, slot]
                    if ring_row[k, slot] != sy:
                        x_sum[:] = 0
                        for kx in range(views.shape[1]):
                            _add_row(x_sum, views[ky, kx, sy], channels, s, src_cols,
                                     first_x[k, kx], ntaps_x[k, kx], w_x[k, kx], lo_x[k, kx], hi_x[k, kx])
                        ring_row[k, slot] = sy
                    _add_weighted(dst, x_sum, w_y[k, ky, r, t])
    _normalise(acc, count_y, count_x, channels, row0, out)



@numba.njit(cache=True, nogil=True)
def _add_rows_taps(xs, view, sy0, sy1, sy_base, channels, n, f, nt, w, lo, hi):
    """``xs[sy − sy_base, q] += Σ_t w[t]·view[sy, clamp(q + f + t)]`` for outputs q = lo … hi of the source
    rows ``sy0 … sy1`` of one view (upsample 1): the clamped ends one sample at a time, the interior as
    one loop nest over rows and contiguous columns (vectorised), so the per-call work is done once per
    view and slice rather than once per row."""
    qa = max(lo, -f)
    qb = min(hi, n - nt - f)
    if qa > qb:
        for sy in range(sy0, sy1 + 1):
            _add_taps_clamped(xs[sy - sy_base], view[sy], channels, 1, 0, n, f, nt, w, lo, hi)
        return
    if lo < qa or qb < hi:
        for sy in range(sy0, sy1 + 1):
            _add_taps_clamped(xs[sy - sy_base], view[sy], channels, 1, 0, n, f, nt, w, lo, qa - 1)
            _add_taps_clamped(xs[sy - sy_base], view[sy], channels, 1, 0, n, f, nt, w, qb + 1, hi)
    e0 = qa * channels
    e1 = (qb + 1) * channels
    off = f * channels
    w0 = w[0]
    if nt == 1:
        for sy in range(sy0, sy1 + 1):
            d = xs[sy - sy_base, e0:e1]
            s0 = view[sy, e0 + off:e1 + off]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i]
    elif nt == 2:
        w1 = w[1]
        for sy in range(sy0, sy1 + 1):
            d = xs[sy - sy_base, e0:e1]
            s0 = view[sy, e0 + off:e1 + off]
            s1 = view[sy, e0 + off + channels:e1 + off + channels]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i]
    else:
        w1 = w[1]
        w2 = w[2]
        w3 = w[3]
        for sy in range(sy0, sy1 + 1):
            d = xs[sy - sy_base, e0:e1]
            s0 = view[sy, e0 + off:e1 + off]
            s1 = view[sy, e0 + off + channels:e1 + off + channels]
            s2 = view[sy, e0 + off + 2 * channels:e1 + off + 2 * channels]
            s3 = view[sy, e0 + off + 3 * channels:e1 + off + 3 * channels]
            for i in range(d.shape[0]):
                d[i] += w0 * s0[i] + w1 * s1[i] + w2 * s2[i] + w3 * s3[i]


@numba.njit(cache=True, nogil=True)
def _interpolated_rows_band(views, channels, first_y, ntaps_y, w_y, lo_y, hi_y,
                            first_x, ntaps_x, w_x, lo_x, hi_x, count_y, count_x, row0, row1, part_kind, out):
    """Output rows ``row0 … row1 − 1`` of every slice at ``upsample = 1`` with fractional positions: the
    plans' phase-0 arrays (``first_*``, ``ntaps_*``, ``lo_*``, ``hi_*`` (K, m); ``w_*`` (K, m, 4)).

    For a view row ky, each view (a few tens of KB, cache-resident) is x-resampled into the per-slice
    partial sums ``xs[k, sy]`` of every slice, all the rows that slice reads at once
    (:func:`_add_rows_taps`); then every output row adds its y-taps' weighted partial sums. The same sums, weights and order of
    additions per slice as :func:`_interpolated_band` with ``s = 1``, which serves upsampled slices.
    """
    m = views.shape[0]
    src_rows = views.shape[2]
    src_cols = views.shape[3] // channels
    n_slices, _, row_len = out.shape
    acc = np.zeros((n_slices, row1 - row0, row_len))
    need_lo = np.empty(n_slices, dtype=np.int64)
    need_hi = np.empty(n_slices, dtype=np.int64)
    for ky in range(m):
        sy_lo, sy_hi = _source_rows(ky, row0, row1, first_y, ntaps_y, lo_y, hi_y, src_rows, need_lo, need_hi)
        if sy_lo > sy_hi:
            continue
        xs = np.zeros((n_slices, sy_hi - sy_lo + 1, row_len), dtype=part_kind.dtype)
        for kx in range(views.shape[1]):
            view = views[ky, kx]
            for k in range(n_slices):
                lo = lo_x[k, kx]
                hi = hi_x[k, kx]
                if lo > hi or need_lo[k] > need_hi[k]:
                    continue
                _add_rows_taps(xs[k], view, need_lo[k], need_hi[k], sy_lo, channels, src_cols, first_x[k, kx],
                               ntaps_x[k, kx], w_x[k, kx], lo, hi)
        for k in range(n_slices):
            for jy in range(max(row0, lo_y[k, ky]), min(row1 - 1, hi_y[k, ky]) + 1):
                dst = acc[k, jy - row0]
                for t in range(ntaps_y[k, ky]):
                    sy = min(max(jy + first_y[k, ky] + t, 0), src_rows - 1)
                    x_sum = xs[k, sy - sy_lo]
                    _add_weighted(dst, x_sum, w_y[k, ky, t])
    _normalise(acc, count_y, count_x, channels, row0, out)
