"""The all-in-focus image: every lens taken from the refocused slice that is sharp at its own depth.

Up to six slices spanning the estimated ``a`` are rendered in one fused call of
:func:`lfproc.refocus` (all views, all channels); each lens blends the two slices that bracket its
estimate, linearly in ``a``. Lenses whose depth is unknown use their best (unconfident) estimate: on a
textureless surface every slice looks the same anyway.
"""

from __future__ import annotations

import numpy as np

#: the most slices rendered for the all-in-focus image
MAX_ALLFOCUS_SLICES = 6


def allfocus_slices(a_estimate: np.ndarray, center_index: int) -> np.ndarray:
    """Refocus parameters spanning the estimates (1st to 99th percentile), about one DOF apart, at most
    :data:`MAX_ALLFOCUS_SLICES`."""
    from ._search import dof_half_width_a

    finite = a_estimate[np.isfinite(a_estimate)]
    if finite.size == 0:
        return np.array([0.0])
    lo, hi = (float(v) for v in np.percentile(finite, [1, 99]))
    spacing = float(2.0 * dof_half_width_a(lo, center_index))
    count = int(np.clip(np.ceil((hi - lo) / spacing) + 1, 1, MAX_ALLFOCUS_SLICES))
    return np.linspace(lo, hi, count) if count > 1 else np.array([0.5 * (lo + hi)])


def allfocus(views: np.ndarray, a_estimate: np.ndarray, center_index: int,
             interpolation: str = "cubic", view_shifts=None, view_mask=None) -> np.ndarray:
    """``(Ny, Nx, C)`` float32: each lens from the slices bracketing its ``a`` (module docstring);
    ``view_shifts``: the per-view shift table the estimates were swept with (``None``: Eq. 9); ``view_mask``:
    the views that carry light, the only ones averaged (as the light field's slices average them)."""
    from ..lightfield import LightField
    from ..refocusing import refocus

    a_slices = allfocus_slices(a_estimate, center_index)
    lf = LightField.from_views(views, view_mask=None if view_mask is None or np.all(view_mask) else view_mask)
    stack = refocus(lf, a_slices, interpolation=interpolation, view_shifts=view_shifts)
    if len(a_slices) == 1:
        return np.maximum(stack[0], 0.0)
    a = np.clip(np.nan_to_num(a_estimate, nan=float(np.median(a_slices))), a_slices[0], a_slices[-1])
    pos = (a - a_slices[0]) / (a_slices[1] - a_slices[0])
    i0 = np.clip(np.floor(pos).astype(np.int64), 0, len(a_slices) - 2)
    t = (pos - i0).astype(np.float32)[..., None]
    first = np.take_along_axis(stack, i0[None, :, :, None], axis=0)[0]
    second = np.take_along_axis(stack, (i0 + 1)[None, :, :, None], axis=0)[0]
    return np.maximum((1.0 - t) * first + t * second, 0.0).astype(np.float32)
