"""Matching cost of a sweep over the refocus parameter ``a``: the spread of the views behind each lens.

For a scene point in focus at ``a`` every view ``k`` shows it at lens ``j + a·(c − k)`` (the contract's
centred Eq. 9), so the samples that the refocused slice ``a`` averages all agree there: their variance
across the views is only noise. Out of focus they sample different points and the variance grows
(the *correspondence* cue). The variance is ``E[Y²] − E[Y]²`` over the views, and both means are what
:func:`lfproc.refocus` computes when it refocuses a light field whose channels are ``Y`` and ``Y²``:
the whole cost volume is one call of the fused multi-slice kernel, one pass over the views.

Views outside the main lens aperture carry no light (decoded: noise divided by a dark white image);
they are weighted 0 through a third channel ``w`` (the mean of ``w`` normalises the weighted means).
With many views a sub-lattice of every ``step``-th view around the central one is used: the same
baseline at a fraction of the cost, its refocus parameter ``step·a``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: luminance weights (Rec. 709) for colour light fields
LUMA_WEIGHTS = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)

#: view samples (views × lenses) above which the sweep uses every second view (or more)
FULL_VIEW_BUDGET = 20_000_000


@dataclass(frozen=True, eq=False)
class CostVolume:
    """The sweep's cost and refocused luminance, both ``(K, Ny, Nx)`` float32, at refocus parameters ``a``."""

    a: np.ndarray           # (K,) float64, increasing
    cost: np.ndarray        # variance of the views' luminance behind each lens, per slice
    luminance: np.ndarray   # the refocused luminance (the slice itself), per slice
    view_step: int


def auto_view_step(m_hat: int, lens_count: int) -> int:
    """The smallest view step whose sub-lattice of views stays within :data:`FULL_VIEW_BUDGET` samples."""
    c = (m_hat - 1) // 2
    for step in range(1, max(c, 1) + 1):
        n = 2 * (c // step) + 1
        if n * n * lens_count <= FULL_VIEW_BUDGET or n <= 3:
            return step
    return 1


def luminance(views: np.ndarray) -> np.ndarray:
    """``(…, C)`` float32 → ``(…)`` float32: Rec. 709 luma for three channels, the mean otherwise."""
    if views.shape[-1] == 3:
        return np.tensordot(views, LUMA_WEIGHTS, axes=([-1], [0])).astype(np.float32, copy=False)
    return views.mean(axis=-1, dtype=np.float32)


def sweep_views(views: np.ndarray, view_step: int, view_weight: np.ndarray | None) -> np.ndarray:
    """The light field the sweep refocuses: channels ``w·Y``, ``w·Y²`` (and ``w`` when weights vary).

    Parameters
    ----------
    views : ndarray (m̂, m̂, Ny, Nx, C)
    view_step : int
        Use views ``c ± step·t`` only.
    view_weight : ndarray (m̂, m̂) or None
        Weight of each view (0 = outside the aperture); ``None`` = all 1.
    """
    m = views.shape[0]
    c = (m - 1) // 2
    picked = np.arange(c % view_step, m, view_step)
    sub = views[np.ix_(picked, picked)]
    y = luminance(sub)
    if view_weight is None or np.all(view_weight[np.ix_(picked, picked)] == 1):
        return np.stack([y, y * y], axis=-1)
    w = view_weight[np.ix_(picked, picked)].astype(np.float32)[:, :, None, None]
    wy = w * y
    return np.stack([wy, wy * y, np.broadcast_to(w, y.shape)], axis=-1)


def cost_volume(views: np.ndarray, a_values, *, view_step: int = 1, view_weight: np.ndarray | None = None,
                interpolation: str = "linear") -> CostVolume:
    """Variance across the views behind every lens for each refocus parameter (one fused refocus call).

    Parameters
    ----------
    views : ndarray (m̂, m̂, Ny, Nx, C)
    a_values : sequence of float
        Refocus parameters of the sweep.
    view_step, view_weight
        See :func:`sweep_views`.
    interpolation : str
        Interpolation of the refocus kernel between lenses.

    Returns
    -------
    CostVolume
    """
    from ..refocus import refocus

    a = np.asarray(a_values, dtype=np.float64)
    stack = refocus(sweep_views(views, view_step, view_weight), a * view_step, interpolation=interpolation)
    if stack.shape[-1] == 3:
        weight = np.maximum(stack[..., 2], np.float32(1e-6))
        mean, mean_sq = stack[..., 0] / weight, stack[..., 1] / weight
    else:
        mean, mean_sq = stack[..., 0], stack[..., 1]
    cost = np.maximum(mean_sq - mean * mean, np.float32(0))
    return CostVolume(a, cost, mean, view_step)
