"""How much of a refocused slice the views reach (Eq. 9 shifts view k by a·(c − k) lenses).

Near the border, the shifted views fall off the lens grid and a slice pixel averages fewer views: it
is less refocused (its depth of field is that of the fewer views) and noisier. The band is |a|·c lenses
wide on each side. A view whose shift reaches N − 1 lenses along an axis leaves the image altogether:
at a large enough |a| only the central views remain, and the "slice" is little more than the central
view (a garbage a that still looks like an answer).
"""

from __future__ import annotations

import numpy as np

#: a slice needs at least this share of the views to overlap the image somewhere
MIN_OVERLAPPING_VIEWS = 0.5


def full_view_fraction(a, m_hat: int, lens_shape: tuple[int, int]) -> np.ndarray:
    """Share of the slice's pixels that average all m̂ × m̂ views, per ``a`` (0 … 1)."""
    c = (m_hat - 1) / 2
    a = np.abs(np.asarray(a, dtype=np.float64))
    share = [np.clip((n - 2.0 * a * c) / n, 0.0, 1.0) for n in lens_shape]
    return share[0] * share[1]


def overlapping_view_fraction(a, m_hat: int, lens_shape: tuple[int, int]) -> np.ndarray:
    """Share of the m̂ × m̂ views that reach at least one pixel of the slice, per ``a``.

    View k reaches the image along an axis of N lenses when its shift |a·(c − k)| is below N − 1.
    """
    c = (m_hat - 1) // 2
    a = np.abs(np.asarray(a, dtype=np.float64))[..., None]
    offsets = np.abs(np.arange(m_hat) - c)
    counts = [np.sum(a * offsets < n - 1, axis=-1) for n in lens_shape]
    return counts[0] * counts[1] / float(m_hat * m_hat)


def max_usable_a(m_hat: int, lens_shape: tuple[int, int], min_fraction: float = MIN_OVERLAPPING_VIEWS) -> float:
    """The bound on |a| below which at least ``min_fraction`` of the views overlap the image (exclusive).

    The share only drops where a view's shift reaches N − 1, i.e. at |a| = (N − 1)/d for an offset
    d = 1 … c, and never rises with |a|: the bound is the first of those at which it is too low.
    """
    c = (m_hat - 1) // 2
    for step in sorted({(n - 1) / d for n in lens_shape for d in range(1, c + 1)}):
        if overlapping_view_fraction(step, m_hat, lens_shape) < min_fraction:
            return step
    return float("inf")


#: a slice is refused when fewer than this share of its pixels average at least half the summed views
MIN_REFOCUSED_AREA = 0.5


def _views_inside(a, m_hat: int, n: int) -> np.ndarray:
    """``(K, m̂, n)`` booleans: whether view k's sample for output index j lies in the array (0 ≤ j + a·(c − k) ≤ n − 1)."""
    c = (m_hat - 1) // 2
    a = np.atleast_1d(np.asarray(a, dtype=np.float64))[:, None, None]
    pos = np.arange(n)[None, None, :] + a * (c - np.arange(m_hat))[None, :, None]
    return (pos >= 0) & (pos <= n - 1)


def refocused_fraction(a, view_mask, lens_shape: tuple[int, int]) -> np.ndarray:
    """Share of a slice's pixels that average at least half of the summed views, per ``a`` (0 … 1).

    ``view_mask`` ((m̂, m̂) booleans, or an int m̂ for every view) marks the views the slice sums. The
    views reaching output (jy, jx) number ``inside_y[jy]ᵀ · mask · inside_x[jx]``: one small matrix
    product per slice.
    """
    mask = np.ones((view_mask, view_mask), bool) if np.ndim(view_mask) == 0 else np.asarray(view_mask, bool)
    m = mask.shape[0]
    inside_y = _views_inside(a, m, lens_shape[0]).astype(np.float64)
    inside_x = _views_inside(a, m, lens_shape[1]).astype(np.float64)
    reached = np.einsum("kvp,vw,kwq->kpq", inside_y, mask.astype(np.float64), inside_x)
    share = (reached >= 0.5 * mask.sum()).mean(axis=(1, 2))
    return share if np.ndim(a) else share[0]


def usable_a_bound(view_mask, lens_shape: tuple[int, int], min_area: float = MIN_REFOCUSED_AREA) -> float:
    """The largest |a| whose slice keeps at least ``min_area`` of its pixels refocused (:func:`refocused_fraction`).

    The share never rises with |a| (every view's span N − |a·(c − k)| shrinks) and is the same for ±a;
    found by bisection to 1e-4 of a lens per view step.
    """
    lo, hi = 0.0, float(max(lens_shape))
    if refocused_fraction(hi, view_mask, lens_shape) >= min_area:
        return hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if refocused_fraction(mid, view_mask, lens_shape) >= min_area:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-4:
            break
    return lo
