"""How much of a refocused slice every view reaches (Eq. 9 shifts view k by a·(c − k) lenses).

Near the border, the shifted views fall off the lens grid and a slice pixel averages fewer views: it
is less refocused (its depth of field is that of the fewer views) and noisier. The band is a·c lenses
wide on each side; once 2·|a|·c exceeds N − 1 no pixel sees all views, and at |a|·c ≥ N − 1 the
outermost views leave the image altogether.
"""

from __future__ import annotations

import numpy as np


def full_view_fraction(a, m_hat: int, lens_shape: tuple[int, int]) -> np.ndarray:
    """Share of the slice's pixels that average all m̂ × m̂ views, per ``a`` (0 … 1)."""
    c = (m_hat - 1) / 2
    a = np.abs(np.asarray(a, dtype=np.float64))
    share = [np.clip((n - 2.0 * a * c) / n, 0.0, 1.0) for n in lens_shape]
    return share[0] * share[1]


def max_full_view_a(m_hat: int, lens_shape: tuple[int, int]) -> float:
    """The largest |a| at which some pixel still averages every view: 2·|a|·c ≤ min(Ny, Nx) − 1."""
    c = (m_hat - 1) / 2
    if c == 0:
        return float("inf")
    return (min(lens_shape) - 1) / (2.0 * c)
