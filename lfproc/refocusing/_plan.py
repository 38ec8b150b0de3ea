"""Sampling plans of the refocus kernels: per slice and axis, which lenses each output sample reads and
with which weights (pure numpy; see the package docstring for the conventions)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

#: positions closer than this (in lenses) to an integer are snapped to it
SNAP_TOLERANCE = 1e-9


# ----------------------------------------------------------------------------- sampling plans (pure numpy)
#: Keys' cubic convolution parameter of each cubic interpolation: ``"cubic"`` is Catmull-Rom (−0.5, exact
#: for quadratics); ``"cubic-sharp"`` (−0.9) lifts the response between lenses so that, on textures of
#: power ∝ 1/f², a slice's full-band variance no longer peaks at integer a (other spectra and a band-
#: limited sharpness it misses: docs/microscope-imaging.md). ``"cubic-spline"`` (B-spline weights here,
#: the recursive filter on each slice afterwards) is in ._spline.
KEYS_PARAMETER = {"cubic": -0.5, "cubic-sharp": -0.9}


def keys_cubic_weights(t: np.ndarray, alpha: float = -0.5) -> np.ndarray:
    """Weights of the four taps ``floor(pos) − 1 … floor(pos) + 2`` for fraction ``t``: Keys' cubic
    convolution with parameter ``alpha`` (Keys 1981, Eq. 15).

    ``alpha = −0.5`` is the Catmull-Rom spline. For any ``alpha`` the weights sum to one and reproduce the
    sample at ``t = 0``. Returns an array shaped ``t.shape + (4,)``.
    """
    t = np.asarray(t, dtype=np.float64)
    u = 1.0 - t
    near = lambda x: ((alpha + 2.0) * x - (alpha + 3.0)) * x * x + 1.0            # |x| ≤ 1
    far = lambda x: ((alpha * x - 5.0 * alpha) * x + 8.0 * alpha) * x - 4.0 * alpha  # 1 < |x| < 2
    return np.stack([far(1.0 + t), near(t), near(u), far(1.0 + u)], axis=-1)


def bspline_weights(t: np.ndarray) -> np.ndarray:
    """Weights of the cubic B-spline on the taps ``floor(pos) − 1 … floor(pos) + 2`` for fraction ``t``
    (``t.shape + (4,)``); they sum to one, and at ``t = 0`` they are (1/6, 2/3, 1/6, 0)."""
    t = np.asarray(t, dtype=np.float64)
    u = 1.0 - t
    return np.stack([u ** 3 / 6.0, (4.0 - 6.0 * t ** 2 + 3.0 * t ** 3) / 6.0,
                     (1.0 + 3.0 * t + 3.0 * t ** 2 - 3.0 * t ** 3) / 6.0, t ** 3 / 6.0], axis=-1)


def snap(x: np.ndarray) -> np.ndarray:
    """``x`` with values within :data:`SNAP_TOLERANCE` of an integer replaced by that integer."""
    x = np.asarray(x, dtype=np.float64)
    nearest = np.round(x)
    return np.where(np.abs(x - nearest) < SNAP_TOLERANCE, nearest, x)


@dataclass(frozen=True)
class AxisPlan:
    """Where the output samples along one axis read each view: the separable half of Eq. 9.

    Output index ``p = q·s + r`` (phase ``r`` of the upsampling ``s``) reads view index ``v`` of slice
    ``k`` at position ``q + offset[k, v, r]``; it counts when ``lo[k, v, r] ≤ q ≤ hi[k, v, r]``
    (``lo > hi``: never) and then takes the taps ``q + first + t`` (``t < ntaps``, clamped to the
    array) with ``weights[..., t]``.
    """

    offset: np.ndarray   # (K, m, s) float64, snapped r/s + a·(c − v)
    first: np.ndarray    # (K, m, s) int64
    ntaps: np.ndarray    # (K, m, s) int64: 1, 2 or 4
    weights: np.ndarray  # (K, m, s, 4) float64, unused taps 0
    lo: np.ndarray       # (K, m, s) int64
    hi: np.ndarray       # (K, m, s) int64
    count: np.ndarray    # (K, P) int64: number of views that count at each output index
    spline: np.ndarray   # (K,) bool

    def inside(self, n: int, upsample: int) -> np.ndarray:
        """``(K, m, P)`` booleans: whether view v's sample counts at output index p (as ``count`` sums)."""
        p = np.arange((n - 1) * upsample + 1)
        q_of_p, r_of_p = p // upsample, p % upsample
        return (self.lo[:, :, r_of_p] <= q_of_p) & (q_of_p <= self.hi[:, :, r_of_p])

    @property
    def whole_lens(self) -> bool:
        """True when every sample is a single unit-weight tap (a pure gather)."""
        return bool(np.all(self.ntaps == 1) and np.all(self.weights[..., 0] == 1.0))


def axis_plan(slopes, m: int, n: int, upsample: int, interpolation: str, factors=None) -> AxisPlan:
    """Sampling plan of one axis of length ``n`` for slices ``slopes`` of an m̂ = ``m`` light field.

    View index v of slice a is read at ``a·(c − v)`` lenses (Eq. 9, centred), or at ``a·factors[v]``
    where a per-view multiplier table ``factors`` (length m) is given (e.g. the sine condition's shifts
    of a microscope view, :func:`lfproc.geometry.refocus_slopes`).
    """
    s = upsample
    c = (m - 1) // 2
    a = np.asarray(slopes, dtype=np.float64)[:, None, None]
    v = np.arange(m)[None, :, None]
    step = (c - v) if factors is None else np.asarray(factors, dtype=np.float64).reshape(1, m, 1)
    r = np.arange(s)[None, None, :]
    with np.errstate(invalid="ignore", over="ignore"):     # |a| near 1e308 gives ±inf: outside
        offset = snap(r / s + a * step)
    q_len = np.where(r == 0, n, n - 1)                       # outputs per phase: P = (n − 1)·s + 1
    lo_f = np.maximum(0.0, np.ceil(-offset))
    hi_f = np.minimum(q_len - 1.0, np.floor(n - 1.0 - offset))
    lo = np.clip(lo_f, -1, n + 1).astype(np.int64)
    hi = np.clip(hi_f, -1, n + 1).astype(np.int64)
    valid = lo <= hi
    spline = np.zeros(len(offset), dtype=bool)
    safe = np.where(valid, offset, 0.0)                      # keeps huge |a| away from int conversion
    weights = np.zeros(offset.shape + (4,))
    if interpolation == "nearest":
        first = np.floor(safe + 0.5)
        ntaps = np.ones(offset.shape, dtype=np.int64)
        weights[..., 0] = 1.0
    else:
        base = np.floor(safe)
        frac = safe - base
        whole = frac == 0.0
        if interpolation == "linear":
            first = base
            ntaps = np.where(whole, 1, 2).astype(np.int64)
            weights[..., 0] = 1.0 - frac
            weights[..., 1] = frac
        elif interpolation == "cubic-spline":
            # a slice with any sample between lenses takes B-spline weights everywhere, whole lenses
            # included (1/6, 2/3, 1/6: the filter of its sum turns them back into the lenses); a slice
            # of whole lenses alone stays a gather
            spline = ~whole.reshape(len(whole), -1).all(axis=1)
            between = spline[:, None, None]
            first = np.where(between, base - 1.0, base)
            ntaps = np.where(between, 4, np.ones(offset.shape, dtype=np.int64))
            weights[...] = np.where(between[..., None], bspline_weights(frac), np.array([1.0, 0.0, 0.0, 0.0]))
        else:
            first = np.where(whole, base, base - 1.0)
            ntaps = np.where(whole, 1, 4).astype(np.int64)
            weights[...] = np.where(whole[..., None], np.array([1.0, 0.0, 0.0, 0.0]),
                                    keys_cubic_weights(frac, KEYS_PARAMETER[interpolation]))
    c_order = np.ascontiguousarray     # one memory layout, so the kernels compile once per dtype
    plan = AxisPlan(offset=c_order(offset), first=c_order(first, dtype=np.int64), ntaps=c_order(ntaps),
                    weights=c_order(weights), lo=c_order(lo), hi=c_order(hi), count=np.zeros((0, 0), np.int64),
                    spline=spline)
    return dataclasses.replace(plan, count=c_order(plan.inside(n, s).sum(axis=1), dtype=np.int64))


