"""Triangulation between two virtual cameras G views apart (Hahne et al., IJCV 2018, Section 4; PlenoptiSign).

Views i and i + G of the light field are two cameras with baseline B_G and relatively tilted axes;
a point whose images in them lie Δx view pixels (lenses) apart sits at a distance that follows from
the same ray model as the refocused slices: views G apart see a point of slice a with a disparity of
−a·G lenses (the contract's Eq. 9 shifts view k by a·(c − k)). So the distance of disparity Δx is the
central slice distance at a' = −Δx/G, and every property of :func:`~lfproc.geometry.slice_distance_mm`
(closed form, exact at infinity, finite exit pupil) carries over.

Signs follow PlenoptiSign 1.1.3 so that its numbers and ours compare one to one: G > 0 means the
second view has the larger view index, B_G = −G·δ·f_U/(1 − ε/d_A) is the second camera's position
relative to the first, Φ_G = arctan(G·δ·ε/f_U) its tilt, and Z = B_G·f_U/(Δx·p_m·(1 − ε/d_A) − G·δ·ε)
the distance from the virtual cameras' plane (its own reference; we add it to the sensor distance).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature
from ._main_lens import main_lens_of
from ._slices import _distance_at, _slope_step


@dataclass(frozen=True, eq=False)
class Triangulation:
    """Result of :func:`triangulate`: arrays broadcast from the inputs (floats for scalar inputs).

    Attributes
    ----------
    gap : G, views apart
    disparity_px : Δx in view pixels (lenses), as measured (relative to slice ``a``)
    baseline_mm : B_G, signed as PlenoptiSign's
    tilt_deg : Φ_G, signed as PlenoptiSign's
    range_mm : Z from the plane of the virtual cameras (PlenoptiSign's Z; negative beyond infinity)
    distance_mm : the point's distance from the sensor; ``inf`` where the rays do not meet in front
        of the camera, NaN where the disparity is NaN
    """

    gap: np.ndarray
    disparity_px: np.ndarray
    baseline_mm: np.ndarray
    tilt_deg: np.ndarray
    range_mm: np.ndarray
    distance_mm: np.ndarray

    def records(self) -> list[dict]:
        """One dict per disparity with the contract's JSON keys (``gap``, ``disparity_px``, ``baseline_mm``,
        ``tilt_deg``, ``distance_mm``) plus ``range_mm``."""
        cols = np.broadcast_arrays(*(np.atleast_1d(np.asarray(getattr(self, k), dtype=np.float64)) for k in
                                     ("gap", "disparity_px", "baseline_mm", "tilt_deg", "distance_mm", "range_mm")))
        return [dict(gap=int(g) if float(g).is_integer() else float(g), disparity_px=float(dx), baseline_mm=float(b),
                     tilt_deg=float(t), distance_mm=float(d), range_mm=float(z))
                for g, dx, b, t, d, z in zip(*(c.ravel() for c in cols))]


def triangulate(camera: Camera, disparity_px, gap=1, a=0.0) -> Triangulation:
    """Baseline B_G, tilt Φ_G and distance of points seen with disparity Δx between views G apart.

    Parameters
    ----------
    camera : Camera
    disparity_px : float or array_like
        Δx: the position of the point in view i + G minus its position in view i, in view pixels
        (one pixel per micro lens). NaN gives a NaN distance.
    gap : int or array_like
        G, the view index difference (not 0); negative swaps the two views.
    a : float or array_like
        The slice the views were aligned on before measuring Δx (as :func:`lfproc.refocus` shifts
        them): 0 for raw views; the raw disparity is Δx − a·G.

    Returns
    -------
    Triangulation
        Broadcast over the inputs.

    Raises
    ------
    LfprocError
        For optics other than a main lens (a microscope's views are orthographic: no virtual cameras,
        baselines or tilts).
    """
    lens = main_lens_of(camera, "triangulation between virtual cameras")
    dx = np.asarray(disparity_px, dtype=np.float64)
    g = np.asarray(gap, dtype=np.float64)
    a = np.asarray(a, dtype=np.float64)
    if np.any(g == 0) or not np.all(np.isfinite(g)):
        raise LfprocError("the view gap G must be a non-zero number of views (e.g. `gap=1`)")
    if not np.all(np.isfinite(a)):
        raise LfprocError("the slice a that disparities are measured against must be finite")
    if np.any(np.isinf(dx)):
        raise LfprocError("disparities must be finite numbers of pixels (NaN marks an unknown one)")
    f_u = lens.focal_length_mm
    eps = lens.image_distance_mm - f_u
    delta = _slope_step(camera)
    pupil = 1.0 - pupil_curvature(camera) * eps
    raw = dx - a * g
    baseline = -g * delta * f_u / pupil + 0.0
    tilt = np.degrees(np.arctan(g * delta * eps / f_u)) + 0.0
    denom = raw * camera.mla_pitch_mm * pupil - g * delta * eps
    with np.errstate(divide="ignore", invalid="ignore"):
        range_mm = np.where(denom == 0.0, np.inf, baseline * f_u / denom)
        distance = _distance_at(camera, a - dx / g)
    distance = np.where(np.isnan(dx), np.nan, distance)
    range_mm = np.where(np.isnan(dx), np.nan, range_mm)
    out = [np.broadcast_to(v, np.broadcast(dx, g, a).shape) for v in (g, dx, baseline, tilt, range_mm, distance)]
    if out[0].ndim == 0:
        out = [float(v) for v in out]
    return Triangulation(*out)
