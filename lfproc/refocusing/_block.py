"""Refocusing a rectangular block of the views alone (Eq. 9 centred on the whole light field's central view).

A sweep that needs the mean over part of the aperture (depth's half apertures: the views on one side of
the central row or column) gets it from :func:`lfproc.refocus` with the other views masked, but the kernels
still read every view and add its zeros. The plans are separable, one per axis and view index, so a
block of view rows × view columns is refocused exactly by the same kernels with the plans' rows of
those view indices: the same samples, weights and order of additions for every view of the block, and
none of the others (an exact zero added to a float sum changes nothing, so the sums are bitwise those of
the masked call); only the normalisation differs, and it is done here by the block's own weights.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import LfprocError
from ._plan import AxisPlan, axis_plan
from ._refocus import _interpolation, _render, _slopes, marked_count
from ._spline import postfilter


def _block_plan(plan: AxisPlan, index: slice, n: int) -> AxisPlan:
    """The rows of ``plan`` (one per view index) of the views ``index``, their count recomputed."""
    part = dataclasses.replace(plan, offset=plan.offset[:, index], first=plan.first[:, index],
                               ntaps=plan.ntaps[:, index], weights=plan.weights[:, index], lo=plan.lo[:, index],
                               hi=plan.hi[:, index])
    part = dataclasses.replace(part, **{f: np.ascontiguousarray(getattr(part, f))
                                        for f in ("offset", "first", "ntaps", "weights", "lo", "hi")})
    return dataclasses.replace(part, count=np.ascontiguousarray(part.inside(n, 1).sum(axis=1), dtype=np.int64))


def view_block_plans(a, m: int, shape: tuple[int, int], rows: slice, cols: slice, interpolation: str = "linear"):
    """The sampling plans (y, x) of the views ``rows`` × ``cols`` of an ``m × m`` light field of ``shape``
    lenses for the slices ``a`` (:func:`lfproc.refocusing._plan.axis_plan`, restricted to those views)."""
    slopes, _ = _slopes(np.atleast_1d(np.asarray(a, dtype=np.float64)))
    interpolation = _interpolation(interpolation)
    plan_y = axis_plan(slopes, m, shape[0], 1, interpolation)
    plan_x = axis_plan(slopes, m, shape[1], 1, interpolation)
    return _block_plan(plan_y, rows, shape[0]), _block_plan(plan_x, cols, shape[1])


def view_weight_inside(a, weight: np.ndarray, shape: tuple[int, int], interpolation: str = "linear") -> np.ndarray:
    """``(K, Ny, Nx)`` float32: per slice ``a`` and lens, the sum of ``weight`` (``(m, m)``) over the views whose
    sample lies inside the light field there (the views a refocused slice averages)."""
    m = weight.shape[0]
    plan_y, plan_x = view_block_plans(a, m, shape, slice(None), slice(None), interpolation)
    return marked_count(weight, plan_y, plan_x, shape[0], shape[1])


def refocus_view_block(block: np.ndarray, a, m: int, rows: slice, cols: slice, weight: np.ndarray,
                       interpolation: str = "linear"):
    """Refocused slices of the views ``rows`` × ``cols`` of an ``m × m`` light field, reading only those.

    Parameters
    ----------
    block : ndarray (m_y, m_x, Ny, Nx, C) float32
        The views of the block (``views[rows, cols]``), any values already weighted as wanted.
    a : sequence of float
        Refocus parameters (Eq. 9, view index ``v`` shifted by ``a·(c − v)``, ``c = (m − 1)/2``).
    m : int
        The whole light field's views per axis.
    rows, cols : slice
        The block's view indices (steps of 1).
    weight : ndarray (m_y, m_x)
        The block's view weights: the slices are divided by their sum over the views inside.
    interpolation : str
        As :func:`lfproc.refocus` (no per-view shift table, no upsampling).

    Returns
    -------
    slices : ndarray (K, Ny, Nx, C) float32
        Per slice and lens, the sum of the block's samples inside the light field divided by the sum of
        their ``weight`` (0 where that is 0): with ``block = w·views`` the weighted mean over the block.
    weight_inside : ndarray (K, Ny, Nx) float32
        That sum of ``weight``.
    """
    block = np.ascontiguousarray(block, dtype=np.float32)
    my, mx, ny, nx, channels = block.shape
    if (len(range(*rows.indices(m))), len(range(*cols.indices(m)))) != (my, mx) or {rows.step, cols.step} - {None, 1}:
        raise LfprocError(f"refocus_view_block: a block of {my} x {mx} views does not match rows {rows}, "
                          f"cols {cols} of {m} x {m}")
    plan_y, plan_x = view_block_plans(a, m, (ny, nx), rows, cols, interpolation)
    out = _render(block, plan_y, plan_x, 1).reshape(len(plan_y.count), ny, nx, channels)
    weight_inside = marked_count(weight, plan_y, plan_x, ny, nx)
    for k in range(len(out)):       # the kernels divided by the views inside; divide by their weight instead
        every = np.multiply.outer(plan_y.count[k], plan_x.count[k])
        with np.errstate(divide="ignore", invalid="ignore"):
            out[k] *= np.where(weight_inside[k] > 0, every / weight_inside[k], 0.0).astype(np.float32)[..., None]
    if plan_y.spline.any() or plan_x.spline.any():
        postfilter(out, plan_y.spline, plan_x.spline, 1)
    return out, weight_inside
