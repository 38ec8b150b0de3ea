"""From refocus parameters to object space: the paper's slice distance (Eqs. 13–21) and DOF (Eqs. 23–31).

Every estimate ``a`` is the slice in which its surface is sharpest, so its position is that slice's
position (:func:`lfproc.geometry.slice_geometry`), in the unit and from the origin of the camera's object
space (:attr:`lfproc.camera.Camera.object_space`): millimetres from the sensor for a main lens, micrometres
from the native object plane, positive towards the objective, for a microscope. Its bounds ``[near, far]``
hold both the slice's own depth of field (the camera cannot tell depths inside it apart) and the basin of
the cost (how far ``a`` could be off): near = nearer(near(a), position(a_high)), far = farther(far(a),
position(a_low)), where nearer is the smaller distance from the sensor, or the larger z.

One physical difference enters, through the optics' object space: distances from the sensor have a slice
at infinity, a_∞, and parameters beyond it (a < a_∞) mean infinity, never the "macro" distances that the
paraxial formula gives far below a_∞ (:func:`infinity_parameter`). An afocal objective has none: z is
linear in a. A microscope's sweep refocuses with the shifts refocusing uses (the sine condition's
per-view shifts where the camera refocuses aplanatically, :func:`lfproc.geometry.refocus_slopes`), so its
slice ``a`` is the plane z(a): no correction factor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import SENSOR_MM, ObjectSpace, PositionNames


@dataclass(frozen=True, eq=False)
class MetricDepth(PositionNames):
    """Per lens, in the camera's object space: the position and its bounds (NaN where ``a`` is NaN).

    Attributes
    ----------
    depth : ndarray
        Position of the sharpest slice: mm from the sensor (``inf`` at infinity), or z in µm.
    near, far : ndarray
        Its bounds nearer to and farther from the optics.
    space : ObjectSpace
        Unit and origin (``camera.object_space``). The contract's names ``distance_mm``, ``near_mm``,
        ``far_mm`` / ``z_um``, ``z_near_um``, ``z_far_um`` read the same arrays (``None`` in the other space).
    """

    depth: np.ndarray
    near: np.ndarray
    far: np.ndarray
    space: ObjectSpace = SENSOR_MM


def infinity_parameter(camera) -> float | None:
    """a_∞, the refocus parameter of the slice at infinity, where the camera's object space has one.

    Distances from the sensor (``space.from_sensor``: a main lens) reach infinity at a_∞
    (:func:`lfproc.geometry.infinity_parameter`); an afocal objective's depths from the native object plane
    do not (``None``): every ``a`` is a plane at a finite depth.
    """
    if not camera.object_space.from_sensor:
        return None
    from .. import geometry

    return geometry.infinity_parameter(camera)


def _in_front(a: np.ndarray, a_inf: float | None) -> np.ndarray:
    """``a`` raised to a_∞ where the optics have one (the slice at infinity stands for every a beyond it)."""
    return a if a_inf is None else np.maximum(a, a_inf)


def slice_positions(camera, a, a_inf: float | None) -> np.ndarray:
    """Object-space position of the slices ``a`` for any ``a``: an end of a cost basin may be ±inf (open at an
    end of the sweep) or NaN.

    With a slice at infinity (``a_inf``, :func:`infinity_parameter`): d(a) of
    :func:`lfproc.geometry.slice_geometry`, with a ≤ a_∞ (−inf included) at infinity and a = +inf at the
    nearest distance the lens focuses (its front focal plane, where d(a) tends for a → ∞). Without (an afocal
    objective): z = a·dz/da, linear through the native object plane (:func:`lfproc.geometry.z_per_a_um`), so
    a = ±inf is ±inf.
    """
    from .. import geometry

    a = np.asarray(a, dtype=np.float64)
    if a_inf is None:
        return geometry.z_per_a_um(camera) * a
    safe = np.where(np.isfinite(a), np.maximum(a, a_inf), a_inf)
    position = np.asarray(geometry.slice_geometry(camera, safe).depth, dtype=np.float64)
    position = np.where(a <= a_inf, np.inf, position)
    return np.where(a == np.inf, geometry.front_focal_plane_mm(camera), position)


def metric_depth(camera, a: np.ndarray, a_low: np.ndarray, a_high: np.ndarray, view_extent=None) -> MetricDepth:
    """Positions and bounds of the estimates ``a`` (NaN = unknown) with cost basins ``[a_low, a_high]``.

    ``view_extent``: the extent of the views the sweep summed (the DOF's r, see
    :func:`lfproc.geometry.slice_geometry`); the views the optics fill when ``None``.
    """
    from .. import geometry

    space = camera.object_space
    a = np.asarray(a, dtype=np.float64)
    known = np.isfinite(a)
    a_safe = np.where(known, a, 0.0)
    a_inf = infinity_parameter(camera)
    dof = geometry.slice_geometry(camera, _in_front(a_safe, a_inf), view_extent)
    nearer, farther = (np.minimum, np.maximum) if space.from_sensor else (np.maximum, np.minimum)
    near = nearer(np.asarray(dof.near), slice_positions(camera, np.where(known, a_high, 0.0), a_inf))
    far = farther(np.asarray(dof.far), slice_positions(camera, np.where(known, a_low, 0.0), a_inf))
    nan = np.float64(np.nan)
    return MetricDepth(np.where(known, slice_positions(camera, a_safe, a_inf), nan), np.where(known, near, nan),
                       np.where(known, far, nan), space)
