"""Where is each lens's surface? The depth stage (:func:`lfproc.depth_map`), on the lens grid of the slices.

``lfproc.depth`` combines the variance across views with the sharpest-slice cue (``docs/depth.md``); the
viewer runs it over the ``a`` range of the slices it shows (:func:`sweep_range`) unless the caller has
a depth map already, and keeps per-lens ``a`` (NaN = unknown), distance, confidence, the ``a`` searched
and the method's name in a :class:`FocusDepth` record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import geometry

#: most slices in a sweep (a third of a DOF per step otherwise)
#: default span of the sweep in a, from the slice focused at infinity towards the camera
DEFAULT_SPAN_A = 3.0


@dataclass(frozen=True, eq=False)
class FocusDepth:
    """Per-lens depth the page uses; arrays ``(Ny, Nx)`` on the light field's lens grid.

    Attributes
    ----------
    a : refined refocus parameter where each lens is sharpest
    distance_mm : its distance from the sensor (Eq. 21), ``inf`` at or beyond infinity's ``a``; for a
        microscope its depth z in µm from the native object plane (``lfproc.depth``'s ``z_um``)
    confidence : 0 (no sharpness peak: flat or noisy) to 1 (a clear peak)
    sweep_a : the refocus parameters of the sweep
    method : how the depths were found
    min_confidence : below it a lens's depth is a guess (grey in the depth map, not used for planning)
    """

    a: np.ndarray
    distance_mm: np.ndarray
    confidence: np.ndarray
    sweep_a: np.ndarray
    method: str = "lfproc.depth"
    min_confidence: float = 0.3


def sweep_range(camera, lens_shape, a_values=None) -> tuple[float, float]:
    """The ``a`` interval to sweep.

    With ``a_values``: their range widened by half a slice's DOF on each side, so that a peak at the
    first or last slice is still a peak. Without: from infinity's ``a`` (Eq. 21 with d = ∞) nearer by
    :data:`DEFAULT_SPAN_A`, within the ``a`` that move the outer views by at most a third of the
    image's smaller side.
    """
    c = max(camera.center_index, 1)
    if a_values is not None and len(a_values):
        margin = 0.5 / c
        return float(np.min(a_values)) - margin, float(np.max(a_values)) + margin
    reach = min(lens_shape) / (3.0 * c)  # |a|·c lenses of shift at the outer views: a third of the image
    a_inf = camera.main_optics.usable_range(camera).low
    if not np.isfinite(a_inf):   # no slice at infinity (a microscope): the N_u resolvable depths, |a| <= 1
        return -min(1.0, reach), min(1.0, reach)
    lo = max(a_inf, -reach)
    return lo, max(lo, min(a_inf + DEFAULT_SPAN_A, reach))



def estimate_depth(lf, a_values=None, depth_map=None) -> FocusDepth:
    """Per-lens depth of ``lf`` over the ``a`` range of ``a_values`` (default: from infinity nearer), from
    ``depth_map`` (a :class:`lfproc.depth.DepthMap` already computed) or a new :func:`lfproc.depth_map` run."""
    if depth_map is None:
        from ..depth import depth

        lo, hi = sweep_range(lf.camera, lf.lens_shape, a_values)
        depth_map = depth(lf, a_range=(lo, hi))
    known = np.isfinite(depth_map.a)
    return FocusDepth(np.where(known, depth_map.a, np.nan).astype(np.float32),
                      np.where(known, depth_map.depth, np.nan).astype(np.float32),
                      np.where(known, depth_map.confidence, 0.0).astype(np.float32),
                      np.asarray(depth_map.a_searched, dtype=np.float64), "lfproc.depth: " + str(depth_map.method),
                      min_confidence=0.0)  # lfproc.depth marks what it does not know as NaN itself
