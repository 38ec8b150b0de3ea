"""From refocus parameters to object space: the paper's slice distance (Eqs. 13–21) and DOF (Eqs. 23–31).

Every estimate ``a`` is the slice in which its surface is sharpest, so its position is that slice's
position (:func:`lfproc.geometry.slice_geometry`), in the unit and from the origin of the camera's object
space (``camera.main_optics.object_space``): millimetres from the sensor for a main lens, micrometres
from the native object plane, positive towards the objective, for a microscope. Its bounds ``[near, far]``
hold both the slice's own depth of field (the camera cannot tell depths inside it apart) and the basin of
the cost (how far ``a`` could be off): near = nearer(near(a), position(a_high)), far = farther(far(a),
position(a_low)), where nearer is the smaller distance from the sensor, or the larger z.

Where the sweep runs past the optics' usable range (:meth:`lfproc.camera.MainOptics.usable_range`), a
parameter beyond an end means that end's position: a main lens's slice at infinity, a_∞, stands for every
a below it (never the "macro" distances the paraxial formula gives far below a_∞), its front focal plane
for a → ∞; an afocal objective's range is unbounded and z is linear in a. A microscope's sweep refocuses
with the shifts refocusing uses (the sine condition's per-view shifts where the camera refocuses
aplanatically, :func:`lfproc.geometry.refocus_slopes`), so its slice ``a`` is the plane z(a): no correction
factor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import SENSOR_MM, ObjectSpace


@dataclass(frozen=True, eq=False)
class MetricDepth:
    """Per lens, in the camera's object space: the position and its bounds (NaN where ``a`` is NaN).

    Attributes
    ----------
    depth : ndarray
        Position of the sharpest slice: mm from the sensor (``inf`` at infinity), or z in µm.
    near, far : ndarray
        Its bounds nearer to and farther from the optics.
    space : ObjectSpace
        Unit, origin and direction (``camera.main_optics.object_space``).
    """

    depth: np.ndarray
    near: np.ndarray
    far: np.ndarray
    space: ObjectSpace = SENSOR_MM


def metric_depth(camera, a: np.ndarray, a_low: np.ndarray, a_high: np.ndarray, view_extent=None) -> MetricDepth:
    """Positions and bounds of the estimates ``a`` (NaN = unknown) with cost basins ``[a_low, a_high]``.

    ``view_extent``: the extent of the views the sweep summed (the DOF's r, see
    :func:`lfproc.geometry.slice_geometry`); the views the optics fill when ``None``.
    """
    from .. import geometry

    space = camera.main_optics.object_space
    usable = camera.main_optics.usable_range(camera)
    a = np.asarray(a, dtype=np.float64)
    known = np.isfinite(a)
    a_safe = np.where(known, a, 0.0)
    dof = geometry.slice_geometry(camera, np.maximum(a_safe, usable.low), view_extent)   # a_∞ stands for beyond
    near = space.nearer(np.asarray(dof.near), geometry.slice_positions(camera, np.where(known, a_high, 0.0)))
    far = space.farther(np.asarray(dof.far), geometry.slice_positions(camera, np.where(known, a_low, 0.0)))
    nan = np.float64(np.nan)
    return MetricDepth(np.where(known, geometry.slice_positions(camera, a_safe), nan), np.where(known, near, nan),
                       np.where(known, far, nan), space)
