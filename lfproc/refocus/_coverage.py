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
