"""Which slices a viewer page shows, and which of them is sharpest at each lens."""

from __future__ import annotations

import math

import numpy as np

from .. import geometry
from ..errors import LfprocError

#: most slices on one page (a wider plan is thinned evenly in a)
MAX_SLICES = 48
def scene_slices(camera, focus, max_slices: int = MAX_SLICES, view_extent=None) -> np.ndarray:
    """The fewest slices whose DOFs cover the scene (:func:`lfproc.geometry.plan_depth_range`, as ``--depth-range``).

    The scene's range is the 2nd to 98th percentile of the refocus parameter of the lenses whose
    depth is known with at least ``focus.min_confidence`` (the whole sweep if fewer than 10 are),
    widened by half a slice's DOF at each end. ``view_extent``: the views the slices sum (their DOF).
    """
    confident = (focus.confidence >= focus.min_confidence) & np.isfinite(focus.a)
    a = focus.a[confident] if confident.sum() >= 10 else focus.sweep_a
    a_lo, a_hi = (float(v) for v in np.percentile(a, [2, 98]))
    c = max(camera.center_index, 1)  # widened by half a DOF, about (1 + |a|)/(2c) in a, against estimate errors
    a_lo, a_hi = a_lo - (1 + abs(a_lo)) / (2 * c), a_hi + (1 + abs(a_hi)) / (2 * c)
    usable = camera.main_optics.usable_range(camera)
    far = float(geometry.slice_positions(camera, a_lo))
    near = float(geometry.slice_positions(camera, max(a_hi, usable.low + 1e-6)))
    if not np.isfinite(near):   # a near end beyond the optics' range: one unit of a in from its far end
        near = float(geometry.slice_positions(camera, usable.low + 1.0))
    near = float(camera.main_optics.object_space.nearer(near, far))
    try:  # covers what can be covered (DOFs that shrink to nothing are left out, far part first)
        planned = geometry.plan_depth_range(camera, near, far, max_slices=4 * max_slices, view_extent=view_extent).a
    except LfprocError:  # nothing coverable: even steps in a
        planned = np.array([])
    if len(planned) == 0:   # within the real slices (e.g. infinity to the front focal plane), as focal_stack takes them
        low, high = geometry.usable_a_range(camera)
        a_lo, a_hi = min(max(a_lo, low), high), min(max(a_hi, low), high)
        planned = np.unique(np.linspace(a_lo, a_hi, int(np.clip(np.ceil((a_hi - a_lo) * c) + 1, 2, max_slices))))
    if len(planned) > max_slices:
        planned = np.linspace(planned[0], planned[-1], max_slices)
    return np.asarray(planned, dtype=np.float64)


def slice_intervals_a(camera, a_values, view_extent=None) -> np.ndarray:
    """``(K, 2)``: each slice's DOF as an interval of ``a`` (far limit's a, near limit's a; Eq. 31 inverted)."""
    geo = geometry.slice_geometry(camera, np.atleast_1d(np.asarray(a_values, dtype=np.float64)), view_extent)
    far_a = np.atleast_1d(geometry.position_parameter(camera, geo.far))
    near_a = np.atleast_1d(geometry.position_parameter(camera, geo.near))
    return np.stack([np.minimum(far_a, near_a), np.maximum(far_a, near_a)], axis=1)


#: slice index of lenses whose depth is unknown
UNKNOWN_SLICE = 255


def sharpest_slice(camera, a_values, lens_a: np.ndarray, view_extent=None) -> np.ndarray:
    """Per lens, the index of the slice whose DOF holds the lens's ``a`` (the nearest one where none does;
    among overlapping ones, the one centred nearest); :data:`UNKNOWN_SLICE` where ``a`` is NaN.
    Returns uint8 ``(Ny, Nx)``."""
    a_values = np.asarray(a_values, dtype=np.float64)
    intervals = slice_intervals_a(camera, a_values, view_extent)
    lens_a = np.asarray(lens_a, dtype=np.float64)
    outside = np.maximum(intervals[:, 0, None, None] - lens_a, lens_a - intervals[:, 1, None, None])
    cost = np.maximum(outside, 0.0) + 1e-6 * np.abs(lens_a - a_values[:, None, None])
    index = np.argmin(np.nan_to_num(cost, nan=np.inf), axis=0).astype(np.uint8)
    index[~np.isfinite(lens_a)] = UNKNOWN_SLICE
    return index
