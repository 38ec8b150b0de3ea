"""From refocus parameters to millimetres: the paper's slice distance (Eqs. 13–21) and DOF (Eqs. 23–31).

Every estimate ``a`` is the slice in which its surface is sharpest, so its distance from the sensor is
that slice's distance d_a (:func:`lfproc.geometry.slice_distance_mm`). Its bounds ``[near, far]`` hold
both the slice's own depth of field (the camera cannot tell depths inside it apart) and the basin of
the cost (how far ``a`` could be off): near = min(d_a−, d(a_high)), far = max(d_a+, d(a_low)).
Parameters beyond the slice at infinity (a < a_∞) mean infinity, never the "macro" distances that the
paraxial formula gives far below a_∞.

A microscope's estimates are depths z in µm from the native object plane (positive towards the
objective, :func:`lfproc.geometry.microscope_slices`), bounded the same way: z_near = max(z_near(a),
z(a_high)), z_far = min(z_far(a), z(a_low)). The sweep refocuses with the shifts refocusing uses (the
sine condition's per-view shifts where the camera refocuses aplanatically,
:func:`lfproc.geometry.refocus_slopes`), so its slice ``a`` is the plane z(a): no correction factor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class MetricDepth:
    """Per lens, in mm from the sensor: the distance and its bounds (NaN where ``a`` is NaN).

    For a microscope the ``_mm`` fields are ``None`` and ``z_um``, ``z_near_um``, ``z_far_um`` hold the
    depth from the native object plane and its bounds in µm.
    """

    distance_mm: np.ndarray | None
    near_mm: np.ndarray | None
    far_mm: np.ndarray | None
    z_um: np.ndarray | None = None
    z_near_um: np.ndarray | None = None
    z_far_um: np.ndarray | None = None


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
    if getattr(camera, "microscope", None) is not None:
        return _microscope_depth(camera, a, a_safe, known, a_low, a_high)
    distance = _distance(camera, a_safe)
    dof = geometry.slice_geometry(camera, np.maximum(a_safe, geometry.infinity_parameter(camera)), view_extent)
    near = np.minimum(np.asarray(dof.near_mm), _distance(camera, np.where(known, a_high, 0.0)))
    far = np.maximum(np.asarray(dof.far_mm), _distance(camera, np.where(known, a_low, 0.0)))
    nan = np.float64(np.nan)
    return MetricDepth(np.where(known, distance, nan), np.where(known, near, nan), np.where(known, far, nan))


def _microscope_depth(camera, a, a_safe, known, a_low, a_high) -> MetricDepth:
    from .. import geometry

    zeta = geometry.z_per_a_um(camera)
    geo = geometry.slice_geometry(camera, a_safe)
    upper = np.maximum(geo.z_near_um, zeta * np.where(known, a_high, 0.0))
    lower = np.minimum(geo.z_far_um, zeta * np.where(known, a_low, 0.0))
    nan = np.float64(np.nan)
    return MetricDepth(None, None, None, np.where(known, zeta * a_safe, nan), np.where(known, upper, nan),
                       np.where(known, lower, nan))
