"""Cubic spline interpolation between lenses (``"cubic-spline"``): the recursive filter of each slice.

A view read between lenses as its interpolating cubic spline (Unser, "Splines: a perfect fit for signal
and image processing", IEEE Signal Processing Magazine 16(6), 1999) is the four-tap sum, with the cubic
B-spline's weights (:func:`._plan.bspline_weights`), of the view's B-spline coefficients ``P v``, where
``P`` is the inverse of the sampled B-spline (1/6, 2/3, 1/6): along each axis a causal and an anti-causal
first-order recursive filter with the pole z = √3 − 2 and the gain 6, mirror-symmetric at the ends.

``P`` and the B-spline taps are both convolutions along the same axis, so they commute, and so does the
sum over the views: the mean over the views of ``B_{t_k} P v_k`` equals ``P`` applied to the mean of
``B_{t_k} v_k``. The kernels therefore take the B-spline weights on the views themselves (four taps, as
for Keys' cubic) and :func:`postfilter` runs ``P`` once on each slice (m̂² times less data than the
views) instead of on every view. This is exact wherever a slice averages the same views over the
filter's reach (|z|^d falls below float32 resolution at d ≈ 12 lenses) and no tap is clamped:
everywhere except the border band that views leave and the few lenses inside it and inside the array's
edges, where taps are clamped to the edge (not mirrored) and the mean runs over fewer views — there the
slice is the filtered mean of clamped taps, not the mean of the views' exact splines.
With ``upsample = s`` each phase r of the finer grid is a lens-grid sequence of its own and is filtered
on its own. At whole lenses the spline passes through the lenses; between them its response stays flat
far closer to the lenses' Nyquist frequency than a 4-tap convolution kernel's, so interpolated slices
are as sharp as whole-lens ones (docs/microscope-imaging.md, interpolation bias).
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: the pole of the cubic B-spline's inverse filter
POLE = math.sqrt(3.0) - 2.0

#: terms of the causal filter's start-up sum: |POLE|**HORIZON < 1e-9, far below float32 resolution
HORIZON = 16


def causal_start(n: int) -> np.ndarray:
    """Weights of samples ``0 … len − 1`` in the causal filter's first value for ``n`` samples, mirror-
    symmetric at both ends: the geometric series truncated at :data:`HORIZON` terms, or exact when
    ``n ≤ HORIZON`` (the mirrored signal then has period 2n − 2)."""
    z = POLE
    if n > HORIZON:
        return z ** np.arange(HORIZON)
    if n == 1:
        return np.ones(1)
    k = np.arange(n, dtype=np.float64)
    zn = z ** (n - 1)
    w = z ** k + zn * zn / z ** k
    w[0] = 1.0
    w[-1] = zn
    return w / (1.0 - zn * zn)


@numba.njit(cache=True, nogil=True)
def _filter_axis0(a, start):
    """``P`` along the first axis of ``a`` (n, L) float64, in place, whole rows at a time (vectorised along L)."""
    n, length = a.shape
    if n == 1:
        return
    z = POLE
    end = 6.0 * POLE / (POLE * POLE - 1.0)     # the anti-causal start, gain 6 folded in
    g = 6.0 * POLE
    first = np.zeros(length)
    for k in range(start.shape[0]):
        w = start[k]
        row = a[k]
        for e in range(length):
            first[e] += w * row[e]
    a[0] = first
    for i in range(1, n):
        cur = a[i]
        prev = a[i - 1]
        for e in range(length):
            cur[e] += z * prev[e]
    last = a[n - 1]
    prev = a[n - 2]
    for e in range(length):
        last[e] = end * (last[e] + z * prev[e])
    for i in range(n - 2, -1, -1):
        cur = a[i]
        nxt = a[i + 1]
        for e in range(length):
            cur[e] = z * nxt[e] - g * cur[e]


@numba.njit(cache=True, nogil=True)
def _filter_rows(a, channels, s, r, n, start):
    """``P`` along every row of ``a`` (rows, Px·C) on the samples of phase r: pixels ``q·s + r``, q < n."""
    if n == 1:
        return
    z = POLE
    end = 6.0 * POLE / (POLE * POLE - 1.0)
    g = 6.0 * POLE
    step = s * channels
    for row_index in range(a.shape[0]):
        row = a[row_index]
        for ch in range(channels):
            o = r * channels + ch
            acc = 0.0
            for k in range(start.shape[0]):
                acc += start[k] * row[o + k * step]
            prev = acc
            row[o] = acc
            for q in range(1, n):
                prev = row[o + q * step] + z * prev
                row[o + q * step] = prev
            last = o + (n - 1) * step
            nxt = end * (prev + z * row[last - step])
            row[last] = nxt
            for q in range(n - 2, -1, -1):
                nxt = z * nxt - g * row[o + q * step]
                row[o + q * step] = nxt


def _phase_lengths(points: int, s: int) -> list[int]:
    """Samples of each phase r of an axis of ``points = (n − 1)·s + 1`` outputs: n for r = 0, n − 1 else."""
    n = (points - 1) // s + 1
    return [n] + [n - 1] * (s - 1)


def postfilter(out: np.ndarray, along_y: np.ndarray, along_x: np.ndarray, upsample: int) -> None:
    """Turn summed B-spline samples into cubic spline samples, in place (module docstring).

    ``out`` (K, Py, Px, C) float32 (each slice filtered in float64); ``along_y[k]`` / ``along_x[k]``: slice k was read with B-spline
    weights along that axis (whole-lens slices are not). Each phase of an upsampled axis is filtered on
    its own.
    """
    k_count, py, px, channels = out.shape
    flat = out.reshape(k_count, py, px * channels)
    s = upsample
    for k in range(k_count):
        if not (along_y[k] or along_x[k]):
            continue
        image = flat[k].astype(np.float64)      # one slice: filtered in float64, rounded once
        if along_y[k]:
            for r, n in enumerate(_phase_lengths(py, s)):
                if n > 0:
                    _filter_axis0(image[r::s], causal_start(n))
        if along_x[k]:
            for r, n in enumerate(_phase_lengths(px, s)):
                if n > 0:
                    _filter_rows(image, channels, s, r, n, causal_start(n))
        with np.errstate(over="ignore"):        # beyond float32: inf, reported by the caller
            flat[k] = image
