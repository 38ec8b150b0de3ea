"""Sub-slice refinement: the minimum of the aggregated cost between the slices of the sweep, and how
well it is defined.

Near its minimum the variance across the views grows with the square of the focus error (each view's
sample moves by (a − a*)·(c − k) lenses, and the variance of a smooth texture grows with the square
of the move), so a parabola through the best slice and its two neighbours locates the minimum to a
fraction of the sweep step.

How well it is defined: the *basin* is the interval of ``a`` around the minimum over which the cost
stays below twice its minimum (or below the minimum plus a noise floor, whichever is larger), its
ends interpolated linearly between slices. A textured surface gives a narrow basin; a textureless
one a wide, flat one; a basin that reaches an end of the sweep may continue beyond it.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

#: box size (lenses) over which the cost is averaged before its minimum is sought: 5 × 5 rather than 3 × 3
#: halves the per-lens scatter of the minimum where the cost curve is shallow (large ``|a|`` on demosaiced
#: captures, docs/depth.md); the edge-aware shift keeps it off depth edges
AGGREGATION_WINDOW = 5


@dataclass(frozen=True, eq=False)
class CostMinimum:
    """Per lens ``(Ny, Nx)``: the refined ``a``, the least cost, the basin ``[a_low, a_high]`` and whether
    the best slice lies inside the sweep (a minimum at either end may lie beyond it: not known)."""

    a: np.ndarray
    cost: np.ndarray
    a_low: np.ndarray
    a_high: np.ndarray
    interior: np.ndarray

    def where(self, take: np.ndarray, other: "CostMinimum") -> "CostMinimum":
        """This minimum where ``take`` (``(Ny, Nx)`` bool), ``other`` elsewhere, field by field."""
        return CostMinimum(*(np.where(take, getattr(self, f.name), getattr(other, f.name)) for f in fields(self)))


def aggregate(cost: np.ndarray, window: int = AGGREGATION_WINDOW) -> np.ndarray:
    """Mean of the cost over a ``window`` × ``window`` box of lenses, per slice (edges repeat)."""
    if window <= 1:
        return cost
    from scipy import ndimage

    return ndimage.uniform_filter(cost, size=(1, window, window), mode="nearest")


def aggregate_edge_aware(cost: np.ndarray, window: int = AGGREGATION_WINDOW) -> np.ndarray:
    """:func:`aggregate`, but each lens takes the ``window`` × ``window`` box centred on it or shifted by
    ``window // 2`` lenses along either axis, whichever reaches the least cost: next to a depth edge the
    box that does not straddle it (a lens of a near object beside a far one keeps its own cost curve,
    not a blend of both)."""
    centred = aggregate(cost, window)
    if window <= 1 or min(cost.shape[1:]) <= window:
        return centred
    h = window // 2
    shifts = ((0, h), (0, -h), (1, h), (1, -h))     # (lens axis, lenses)
    best_min = centred.min(axis=0)   # a shifted box's least cost is the centred boxes' least cost, shifted
    centred_min = best_min
    choice = np.zeros(best_min.shape, dtype=np.int8)
    for i, (axis, step) in enumerate(shifts, 1):
        index = np.clip(np.arange(best_min.shape[axis]) + step, 0, best_min.shape[axis] - 1)
        shifted_min = np.take(centred_min, index, axis=axis)
        better = shifted_min < best_min
        if better.any():
            best_min = np.where(better, shifted_min, best_min)
            choice[better] = i
    ys, xs = np.nonzero(choice)
    if ys.size:   # each lens takes its chosen box's cost curve: one gather, not a copy of the volume per shift
        axis, step = np.array(shifts)[choice[ys, xs] - 1].T
        src_y = np.where(axis == 0, np.clip(ys + step, 0, best_min.shape[0] - 1), ys)
        src_x = np.where(axis == 1, np.clip(xs + step, 0, best_min.shape[1] - 1), xs)
        centred[:, ys, xs] = centred[:, src_y, src_x]
    return centred


def parabola_vertex(c0, c1, c2):
    """Vertex offset in steps (clipped to ±0.5: the middle value is the least) and curvature
    ``c0 − 2c1 + c2`` of the parabola through equally spaced values ``c0, c1, c2``."""
    curvature = c0 - 2.0 * c1 + c2
    positive = curvature > 0
    offset = np.where(positive, 0.5 * (c0 - c2) / np.where(positive, curvature, 1.0), 0.0)
    return np.clip(offset, -0.5, 0.5), curvature


def refine_minimum(cost: np.ndarray, a_values: np.ndarray, floor: float) -> CostMinimum:
    """Each lens's cost minimum between the sweep's slices, and its basin.

    Parameters
    ----------
    cost : ndarray (K, Ny, Nx)
        Aggregated cost of the equally spaced, increasing slices ``a_values``.
    a_values : ndarray (K,)
    floor : float
        Cost differences below this are noise: the basin extends at least to ``minimum + floor``.

    Returns
    -------
    CostMinimum
    """
    best, interior, c1, offset, curvature, a = _vertex(cost, a_values)
    c_min = np.maximum(c1 - 0.5 * curvature * offset * offset, 0.0) if cost.shape[0] >= 3 else c1
    level = c_min + np.maximum(c_min, floor)
    a_low, a_high = _basin(cost, np.asarray(a_values, dtype=np.float64), best, level)
    return CostMinimum(a=a, cost=c_min, a_low=np.minimum(a_low, a), a_high=np.maximum(a_high, a), interior=interior)


def minimum_position(cost: np.ndarray, a_values: np.ndarray) -> np.ndarray:
    """The ``a`` of :func:`refine_minimum` alone (no basin): for cost arrays ``(K, …)`` of any lens shape."""
    return _vertex(cost, a_values)[-1]


def _vertex(cost, a_values):
    """Best slice, whether it is interior, its cost, the parabola's offset (steps) and curvature, and ``a``."""
    k = cost.shape[0]
    a_values = np.asarray(a_values, dtype=np.float64)
    step = float(a_values[1] - a_values[0]) if k > 1 else 0.0
    best = np.argmin(cost, axis=0)
    interior = (best > 0) & (best < k - 1)
    take = lambda i: np.take_along_axis(cost, i[None], axis=0)[0].astype(np.float64)
    c1 = take(best)
    if k >= 3:
        offset, curvature = parabola_vertex(take(np.maximum(best - 1, 0)), c1, take(np.minimum(best + 1, k - 1)))
        offset = np.where(interior, offset, 0.0)
    else:
        offset, curvature = np.zeros_like(c1), np.zeros_like(c1)
    return best, interior, c1, offset, curvature, a_values[best] + offset * step


def _basin(cost, a_values, best, level):
    """Ends of the run of slices around ``best`` whose cost stays below ``level``, interpolated to where
    the cost crosses ``level``; ``±inf`` where the run reaches an end of the sweep."""
    k = cost.shape[0]
    idx = np.arange(k)[:, None, None]
    above = cost > level[None]
    # nearest slice below / above best whose cost rises above the level
    below_best = above & (idx < best[None])
    above_best = above & (idx > best[None])
    lo_i = np.where(below_best.any(axis=0), k - 1 - np.argmax(below_best[::-1], axis=0), -1)
    hi_i = np.where(above_best.any(axis=0), np.argmax(above_best, axis=0), k)

    def crossing(outer, inner):
        o = np.clip(outer, 0, k - 1)
        i = np.clip(inner, 0, k - 1)
        co = np.take_along_axis(cost, o[None], 0)[0].astype(np.float64)
        ci = np.take_along_axis(cost, i[None], 0)[0].astype(np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip((level - ci) / (co - ci), 0.0, 1.0)
        return a_values[i] + np.nan_to_num(t) * (a_values[o] - a_values[i])

    a_low = np.where(lo_i >= 0, crossing(lo_i, lo_i + 1), -np.inf)
    a_high = np.where(hi_i < k, crossing(hi_i, hi_i - 1), np.inf)
    return a_low, a_high
