"""From refocus parameters to millimetres: the paper's slice distance (Eqs. 13–21) and DOF (Eqs. 23–31).

Every estimate ``a`` is the slice in which its surface is sharpest, so its distance from the sensor is
that slice's distance d_a (:func:`lfproc.geometry.slice_distance_mm`). Its bounds ``[near, far]`` hold
both the slice's own depth of field (the camera cannot tell depths inside it apart) and the basin of
the cost (how far ``a`` could be off): near = min(d_a−, d(a_high)), far = max(d_a+, d(a_low)).
Parameters beyond the slice at infinity (a < a_∞) mean infinity, never the "macro" distances that the
paraxial formula gives far below a_∞.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class MetricDepth:
    """Per lens, in mm from the sensor: the distance and its bounds (NaN where ``a`` is NaN)."""

    distance_mm: np.ndarray
    near_mm: np.ndarray
    far_mm: np.ndarray


def _distance(camera, a: np.ndarray) -> np.ndarray:
    """d(a) with a below a_∞ (including −inf) as infinity and +inf as the nearest focusable distance."""
    from .. import geometry

    a_inf = geometry.infinity_parameter(camera)
    finite = np.isfinite(a)
    safe = np.where(finite, np.maximum(a, a_inf), a_inf)
    d = np.asarray(geometry.slice_distance_mm(camera, safe), dtype=np.float64)
    d = np.where(np.isfinite(a) & (a <= a_inf), np.inf, d)
    d = np.where(a == -np.inf, np.inf, d)
    return np.where(a == np.inf, camera.sensor_to_main_lens_mm + camera.main_focal_length_mm, d)


def metric_depth(camera, a: np.ndarray, a_low: np.ndarray, a_high: np.ndarray, view_extent=None) -> MetricDepth:
    """Distances and bounds of the estimates ``a`` (NaN = unknown) with cost basins ``[a_low, a_high]``.

    ``view_extent``: the extent of the views the sweep summed (the DOF's c, see
    :func:`lfproc.geometry.slice_geometry`); the full micro image when ``None``.
    """
    from .. import geometry

    a = np.asarray(a, dtype=np.float64)
    known = np.isfinite(a)
    a_safe = np.where(known, a, 0.0)
    distance = _distance(camera, a_safe)
    dof = geometry.slice_geometry(camera, np.maximum(a_safe, geometry.infinity_parameter(camera)), view_extent)
    near = np.minimum(np.asarray(dof.near_mm), _distance(camera, np.where(known, a_high, 0.0)))
    far = np.maximum(np.asarray(dof.far_mm), _distance(camera, np.where(known, a_low, 0.0)))
    nan = np.float64(np.nan)
    return MetricDepth(np.where(known, distance, nan), np.where(known, near, nan), np.where(known, far, nan))
