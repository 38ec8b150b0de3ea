"""Which refocus parameters the sweep visits: only the depths the scene (or the user) asks for.

The sweep is uniform in ``a`` (Eq. 9's shift per view step), with a step of half the depth of field
of the slice at ``a = 0`` in units of ``a``: slice ``a``'s DOF spans a₊ … a₋ with
a∓ = (2ac ∓ 1)/(2c ± 1) (Eqs. 23–31 in the form of :mod:`lfproc.geometry`), a width of
4c(a + 1)/(4c² − 1) ≈ (a + 1)/c, so the step is about 1/(2c). Two extra slices at each end let a
surface at either end of the range have its minimum inside the sweep.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import LfprocError

#: without a depth range, the sweep runs from the slice at infinity to this much nearer (in a)
DEFAULT_A_SPAN = 3.0

#: without a camera and a range, the sweep covers these refocus parameters
DEFAULT_A_RANGE = (-1.0, 3.0)

#: a microscope's default sweep: the N_u resolvable depths of Levoy et al. (2006), |a| <= 1
MICROSCOPE_A_RANGE = (-1.0, 1.0)

#: slices added beyond each end of the range
PADDING_SLICES = 2

#: the most slices one sweep may have (a finer step or a wider range raises LfprocError)
MAX_SWEEP_SLICES = 400


def dof_half_width_a(a, center_index: int) -> np.ndarray:
    """Half the DOF of slice ``a`` in units of ``a``: 2c·|a + 1|/(4c² − 1) (from a∓ above), at least 1/(4c)."""
    c = max(int(center_index), 1)
    a = np.asarray(a, dtype=np.float64)
    return np.maximum(2.0 * c * np.abs(a + 1.0) / (4.0 * c * c - 1.0), 0.25 / c)


def default_step(center_index: int) -> float:
    """Half the DOF width at a = 0 in units of a: 2c/(4c² − 1) ≈ 1/(2c)."""
    c = max(int(center_index), 1)
    return float(2.0 * c / (4.0 * c * c - 1.0))


def search_range_a(camera, depth_range_mm=None, a_range=None) -> tuple[float, float]:
    """The interval of ``a`` to search: from ``a_range``, from ``depth_range_mm`` (needs the camera), or the
    default (from the slice at infinity to :data:`DEFAULT_A_SPAN` nearer, or :data:`DEFAULT_A_RANGE`)."""
    if a_range is not None and depth_range_mm is not None:
        raise LfprocError("give either a depth range in mm or a range of a, not both")
    if a_range is not None:
        lo, hi = (float(v) for v in a_range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise LfprocError(f"range of a {a_range!r} must be two finite numbers LOW < HIGH")
        return lo, hi
    if depth_range_mm is not None:
        from .. import geometry

        if camera is None:
            raise LfprocError("a depth range in mm needs the light field's camera; decode with `camera=`")
        from ..camera import SENSOR_MM

        geometry.require_space(camera, SENSOR_MM, "`depth_range_mm=` (for micrometres give `z_range_um=`)")
        near, far = (float(v) for v in depth_range_mm)
        if not (near > 0 and far >= near) or math.isnan(far):
            raise LfprocError(f"depth range {near}:{far} mm is not a valid range; give NEAR:FAR with 0 < NEAR <= FAR")
        closest = geometry.front_focal_plane_mm(camera)
        if near <= closest:
            raise LfprocError(f"depth range starts at {near} mm, but this camera focuses only beyond {closest:.3f} mm "
                              f"from the sensor; give a larger NEAR")
        hi = float(geometry.refocus_parameter(camera, near))
        lo = float(geometry.refocus_parameter(camera, far))
        return lo, max(hi, lo + 1e-9)
    if camera is not None:
        low = camera.main_optics.usable_range(camera).low
        if not math.isfinite(low):   # no slice at infinity (an afocal objective): the N_u resolvable depths
            return MICROSCOPE_A_RANGE
        return low, low + DEFAULT_A_SPAN   # from the slice at infinity, nearer
    return DEFAULT_A_RANGE


def sweep_parameters(a_low: float, a_high: float, step: float, center_index: int | None = None) -> np.ndarray:
    """Equally spaced ``a`` from ``a_low`` to ``a_high`` (inclusive, rounded outwards) plus padding slices.

    The padding lets the cost's basin around a surface at either end of the range close inside the
    sweep (else the estimate is unknown): :data:`PADDING_SLICES`, or with ``center_index`` (c) as many as
    span the DOF half-width there (:func:`dof_half_width_a`), which grows with ``a``: near slices have a
    wider DOF in units of ``a``, and so a wider basin.
    """
    if not (step > 0 and math.isfinite(step)):
        raise LfprocError(f"sweep step {step!r} must be a positive number (in units of a)")
    pad_low = pad_high = PADDING_SLICES
    if center_index is not None:
        pad_low = max(pad_low, math.ceil(float(dof_half_width_a(a_low, center_index)) / step - 1e-9))
        pad_high = max(pad_high, math.ceil(float(dof_half_width_a(a_high, center_index)) / step - 1e-9))
    first = math.floor(a_low / step + 1e-9) - pad_low
    last = math.ceil(a_high / step - 1e-9) + pad_high
    count = last - first + 1
    if count > MAX_SWEEP_SLICES:
        raise LfprocError(f"the depth search needs {count} slices (more than {MAX_SWEEP_SLICES}); "
                          f"narrow the depth range or use a coarser step")
    return np.round(np.arange(first, last + 1) * step, 12)
