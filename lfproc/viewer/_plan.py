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
    if not camera.object_space.from_sensor:   # signed depths (µm from the native plane), as --z-range
        zeta = geometry.z_per_a_um(camera)
        try:
            planned = geometry.plan_z_range(camera, a_lo * zeta, a_hi * zeta, max_slices=4 * max_slices)
        except LfprocError:   # more than 4x the page's slices: even steps in a
            planned = np.linspace(a_lo, a_hi, max_slices)
        if len(planned) > max_slices:
            planned = np.linspace(planned[0], planned[-1], max_slices)
        return np.asarray(planned, dtype=np.float64)
    a_inf = geometry.infinity_parameter(camera)
    far = math.inf if a_lo <= a_inf else geometry.slice_distance_mm(camera, a_lo)
    near = geometry.slice_distance_mm(camera, max(a_hi, a_inf + 1e-6))
    near = min(near, far) if math.isfinite(near) else geometry.slice_distance_mm(camera, a_inf + 1.0)
    try:  # covers what can be covered (DOFs that shrink to nothing are left out, far part first)
        planned = geometry.plan_depth_range(camera, near, far, max_slices=4 * max_slices, view_extent=view_extent).a
    except LfprocError:  # nothing coverable: even steps in a
        planned = np.array([])
    if len(planned) == 0:   # within the real slices (infinity to the front focal plane), as focal_stack takes them
        low, high = geometry.usable_a_range(camera)
        a_lo, a_hi = min(max(a_lo, low), high), min(max(a_hi, low), high)
        planned = np.unique(np.linspace(a_lo, a_hi, int(np.clip(np.ceil((a_hi - a_lo) * c) + 1, 2, max_slices))))
    if len(planned) > max_slices:
        planned = np.linspace(planned[0], planned[-1], max_slices)
    return np.asarray(planned, dtype=np.float64)


def slice_intervals_a(camera, a_values, view_extent=None) -> np.ndarray:
    """``(K, 2)``: each slice's DOF as an interval of ``a`` (far limit's a, near limit's a; Eq. 31 inverted)."""
    geo = geometry.slice_geometry(camera, np.atleast_1d(np.asarray(a_values, dtype=np.float64)), view_extent)
    if not geo.space.from_sensor:   # signed depths (a microscope's z), linear in a
        zeta = geometry.z_per_a_um(camera)
        return np.stack([geo.z_far_um / zeta, geo.z_near_um / zeta], axis=1)
    a_inf = geometry.infinity_parameter(camera)
    far_a = [a_inf if not math.isfinite(f) else geometry.refocus_parameter(camera, f) for f in geo.far_mm]
    near_a = [geometry.refocus_parameter(camera, n) for n in geo.near_mm]
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
