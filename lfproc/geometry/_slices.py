"""Where each refocused slice is focused: distance and depth of field (Eqs. 13–31), and the inverse.

Pure, vectorised functions of a :class:`~lfproc.camera.Camera` and the refocus parameter ``a``; no
images. Every distance is measured from the sensor, in millimetres.

Closed forms
------------
Write p_m for the micro lens pitch, p_p for the effective pixel pitch (the micro image pitch / m̂),
f_s and f_U for the focal lengths, b_U for the main lens–MLA spacing, ε = b_U − f_U ≥ 0,
δ = p_p / f_s (the slope step between adjacent micro image positions, Eq. 13), κ = 1/d_A (0 for the
telecentric main lens of the 2014 paper, see :mod:`._exit_pupil`) and L = f_s + H1sH2s + b_U + H1UH2U.

Two rays under lenses ΔS = A·p_m apart whose image-side slopes differ by ΔM = δ − C·p_m·κ (per
unit of pixel offset) leave the main lens (Eq. 16) and meet (Eqs. 18–20) at

    x = z − f_U = f_U²·N / (A·p_m + N·ε),     N = δ − C·p_m·κ,

from the front focal plane (Newton's form x·x' = f²), so d = L + f_U + x (Eq. 21).

Central distance (Eqs. 13–21): pixel i under lens j and pixel i + 1 under lens j − a, A = C = a.
Telecentric, d_a = L + f_U + f_U²·δ / (a·p_m + δ·ε): exact at a = 0 (infinite when ε = 0) and
without the cancellation a 2×2 solve of Eq. 20 would suffer up to a = 1e4.

Depth of field (Eqs. 23–31). The extreme pixels merged by Eq. 9 are i = −c under lens j + 2ac and
i = +c under lens j; each pixel's beam fills its micro lens (one lens wide at the MLA) and its pixel
(one view step wide in angle). The slice is sharp where these two beams still overlap. The bounding
border-ray pairs give A = (2ac + s)/(2c + t), C = 2ac/(2c + t) with s = −1 for the far and +1 for
the near limit. The paper (which treats a ≥ 0) always takes t = −s. That is right for a limit in
front of the main lens focus distance (A ≥ 0), where a beam widens as 1 + A lenses; beyond the focus
distance (A < 0) a beam widens as 1 − A and the bounding pair is t = +s (the paper's pair crosses
instead, so its DOF shrinks to zero at a = −1). This module uses the bounding pair on each side
(issue 12, shown with renders in ``docs/exit-pupil.md``); for limits at or in front of the focus
distance, i.e. every a ≥ 1/(2c), the numbers are the paper's.

Each limit is expressed as the central distance of an equivalent parameter
a_eq = A / (1 + (A − C)·p_m·κ/δ) (equal to A when telecentric), so one monotone function d(a)
orders slices and limits alike.

Domain. The rays meet in front of the camera when z > 0: above a_∞ = −δ·ε/(p_m·(1 − κε)), the slice
at infinity, they converge. Between a_0 and a_∞ they diverge: the slice is "beyond infinity" and its
distance is ``inf``. Below a_0 they meet between the main lens and its front focal plane (z < f_U),
a macro regime the paraxial model still describes; distances there are finite and below L + f_U.
With a finite exit pupil, slices far above a = δ·d_A/p_m pass the front focal plane towards the
entrance pupil; where they would meet behind H1U (z ≤ 0) the distance is ``inf``, as PlenoptiSign's
"out of range". Distances are never negative and never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature


def _require_main_lens(camera, what: str) -> None:
    if getattr(camera, "microscope", None) is not None:
        camera.require_main_lens(what)


def _slope_step(camera: Camera) -> float:
    """δ = p_p / f_s with the sample pitch p_p (Eq. 13 for Δu = 1): the micro image pitch over m̂."""
    return camera.sample_pitch_mm / camera.mla_focal_length_mm


def _pair_distance(camera: Camera, shift, spread):
    """(distance, D) where a ray pair (A, C) of the module docstring meets; D = A·p_m + N·ε has the sign of 1/x.

    The distance is ``inf`` where the rays do not meet in front of the main lens (z ≤ 0 or parallel).
    """
    f_u = camera.main_focal_length_mm
    eps = camera.image_distance_mm - f_u
    pitch = camera.mla_pitch_mm
    slope_gap = _slope_step(camera) - spread * pitch * pupil_curvature(camera)   # N; exactly δ when telecentric
    denom = shift * pitch + slope_gap * eps
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        newton_x = f_u * f_u * slope_gap / denom
        z = f_u + newton_x
    z = np.where((z > 0) & np.isfinite(z), z, np.inf)
    return camera.sensor_to_main_lens_mm + z, denom


def _distance_at(camera: Camera, a) -> np.ndarray:
    """d(a) of the module docstring (A = C = a), vectorised; ``inf`` where the rays do not meet in front."""
    a = np.asarray(a, dtype=np.float64)
    return _pair_distance(camera, a, a)[0]


def _equivalent_parameter(camera: Camera, shift, spread):
    """a_eq whose central distance equals the meeting point of a border-ray pair (A, C); A when telecentric."""
    kappa_ratio = camera.mla_pitch_mm * pupil_curvature(camera) / _slope_step(camera)
    return shift / (1.0 + (shift - spread) * kappa_ratio)


def _dof_pairs(camera: Camera, a, center=None):
    """((A₋, C₋), (A₊, C₊)): the border-ray pairs bounding slice a on its near and far side.

    ``center`` replaces c = (m̂ − 1)/2 where fewer views carry light (a microscope's NA).
    """
    c = camera.center_index if center is None else center
    if c == 0:  # m̂ = 1: a single pixel per lens; both borders of the one pixel bound the DOF
        minus_one = np.full_like(a, -1.0)
        return (minus_one, minus_one), (minus_one, minus_one)
    two_ac = 2.0 * a * c
    pairs = []
    for s in (1.0, -1.0):                                # near, far
        # the paper's pair t = -s bounds the beams where the limit is in front of the focus distance
        t = np.where(two_ac + s >= 0.0, -s, s)
        pairs.append(((two_ac + s) / (2.0 * c + t), two_ac / (2.0 * c + t)))
    return pairs[0], pairs[1]


def _dof_parameters(camera: Camera, a):
    """(a₋, a₊): equivalent central parameters of the near and far DOF limit of slice a."""
    a = np.asarray(a, dtype=np.float64)
    near, far = _dof_pairs(camera, a)
    return _equivalent_parameter(camera, *near), _equivalent_parameter(camera, *far)


def slice_distance_mm(camera: Camera, a) -> np.ndarray | float:
    """Central distance d_a of refocused slice ``a`` from the sensor (Eqs. 13–21; finite d_A: Hahne 2018).

    Parameters
    ----------
    camera : Camera
    a : float or array_like
        Refocus parameter (any real value; positive focuses nearer than a = 0).

    Returns
    -------
    float or ndarray
        Distance in mm; ``inf`` where the chief rays are parallel or diverge.
    """
    _require_main_lens(camera, "a slice distance from the sensor")
    d = _distance_at(camera, a)
    return float(d) if d.ndim == 0 else d


@dataclass(frozen=True, eq=False)
class SliceGeometry:
    """Geometry of refocused slices (arrays with the shape of ``a``, or floats for a scalar ``a``).

    Attributes
    ----------
    a : refocus parameter
    distance_mm : d_a, Eq. 21
    near_mm, far_mm : d_a− and d_a+, Eq. 31
    dof_mm : D_a = d_a+ − d_a−, Eq. 23 (``inf`` when the far limit is at infinity)
    z_um, z_near_um, z_far_um, dof_um : for a microscope camera (then the ``_mm`` fields are ``None``):
        object-space depth from the native object plane, positive towards the objective, its DOF
        limits nearer to and farther from the objective, and the DOF (:mod:`._microscope`)
    """

    a: np.ndarray
    distance_mm: np.ndarray | None
    near_mm: np.ndarray | None
    far_mm: np.ndarray | None
    dof_mm: np.ndarray | None
    z_um: np.ndarray | None = None
    z_near_um: np.ndarray | None = None
    z_far_um: np.ndarray | None = None
    dof_um: np.ndarray | None = None

    @property
    def microscope(self) -> bool:
        """True for slices in µm of a microscope (``z_um``…), False for distances in mm from the sensor."""
        return self.z_um is not None

    def records(self) -> list[dict]:
        """One dict per slice with the contract's JSON keys; infinity as ``math.inf``.

        A camera's slices: ``a, distance_mm, near_mm, far_mm, dof_mm``; a microscope's: ``a, z_um,
        z_near_um, z_far_um, dof_um``.
        """
        if self.microscope:
            cols = [np.atleast_1d(np.asarray(x, dtype=np.float64)) for x in
                    (self.a, self.z_um, self.z_near_um, self.z_far_um, self.dof_um)]
            return [dict(a=float(a), z_um=float(z), z_near_um=float(n), z_far_um=float(f), dof_um=float(w))
                    for a, z, n, f, w in zip(*cols)]
        cols = [np.atleast_1d(np.asarray(x, dtype=np.float64)) for x in
                (self.a, self.distance_mm, self.near_mm, self.far_mm, self.dof_mm)]
        return [dict(a=float(a), distance_mm=float(d), near_mm=float(n), far_mm=float(f), dof_mm=float(w))
                for a, d, n, f, w in zip(*cols)]


def slice_geometry(camera: Camera, a) -> SliceGeometry:
    """Distance and depth of field of refocused slices (Eqs. 13–31).

    Parameters
    ----------
    camera : Camera
    a : float or array_like
        Refocus parameters.

    Returns
    -------
    SliceGeometry
        ``near_mm <= distance_mm <= far_mm`` always holds; limits are ``inf`` where the bounding
        rays do not meet in front of the camera. Limits beyond the focus distance use the border
        rays that bound the beams there (see the module docstring), so the DOF never collapses.
        For a microscope camera the ``_um`` fields instead (:func:`~._microscope.microscope_slices`).
    """
    if getattr(camera, "microscope", None) is not None:
        from ._microscope import microscope_slices
        return microscope_slices(camera, a)
    a_arr = np.asarray(a, dtype=np.float64)
    d, d_sign = _pair_distance(camera, a_arr, a_arr)
    near_pair, far_pair = _dof_pairs(camera, a_arr)
    limit1, sign1 = _pair_distance(camera, *near_pair)
    limit2, sign2 = _pair_distance(camera, *far_pair)
    near = np.minimum(np.minimum(limit1, limit2), d)
    far = np.maximum(np.maximum(limit1, limit2), d)
    # D is linear along the border rays' path from the central pair to each limit (up to a positive
    # factor): a sign change on either path means the DOF passes through infinity
    centre_in_front = d_sign > 0
    crosses = (centre_in_front != (sign1 > 0)) | (centre_in_front != (sign2 > 0))
    if camera.center_index == 0:   # one pixel per lens: both limits are the same pair, not a path from the centre
        crosses = np.zeros_like(crosses)
    far = np.where(crosses, np.inf, far)
    in_front = np.minimum(np.where(sign1 > 0, limit1, np.inf), np.where(sign2 > 0, limit2, np.inf))
    near = np.where(crosses, np.minimum(in_front, d), near)
    with np.errstate(invalid="ignore"):
        dof = np.where(np.isinf(far), np.inf, far - near)
    if a_arr.ndim == 0:
        return SliceGeometry(float(a_arr), float(d), float(near), float(far), float(dof))
    return SliceGeometry(a_arr, d, near, far, dof)


def infinity_parameter(camera: Camera) -> float:
    """a_∞ = −δ·ε/(p_m·(1 − κε)): the refocus parameter of the slice focused at infinity (0 when b_U = f_U)."""
    _require_main_lens(camera, "the slice at infinity")
    eps = camera.image_distance_mm - camera.main_focal_length_mm
    return -_slope_step(camera) * eps / (camera.mla_pitch_mm * (1.0 - pupil_curvature(camera) * eps))


def refocus_parameter(camera: Camera, distance_mm) -> np.ndarray | float:
    """The ``a`` whose slice is centred at ``distance_mm`` from the sensor (inverse of Eq. 21).

    a = δ·(f_U²/x − ε) / (p_m·(1 − κε + κ·f_U²/x)) with x = d − L − f_U, the distance from the front
    focal plane (κ = 0 when telecentric).

    Raises
    ------
    LfprocError
        For a distance at or behind the main lens (d ≤ L), or NaN.
    """
    _require_main_lens(camera, "a distance in mm (give depths of a microscope in um, --z-range)")
    d = np.asarray(distance_mm, dtype=np.float64)
    inside = camera.sensor_to_main_lens_mm
    if np.any(np.isnan(d)) or np.any(d <= inside):
        bad = d[np.isnan(d) | (d <= inside)].ravel()[0]
        raise LfprocError(f"distance {bad} mm is not in front of the main lens (it must exceed {inside:.3f} mm "
                          f"from the sensor); give a larger distance")
    f_u = camera.main_focal_length_mm
    eps = camera.image_distance_mm - f_u
    kappa = pupil_curvature(camera)
    x = d - inside - f_u
    with np.errstate(divide="ignore"):
        inv_x = np.where(np.isinf(d), 0.0, 1.0 / x)
    with np.errstate(invalid="ignore"):
        pupil = 1.0 - kappa * eps + kappa * (f_u * f_u * inv_x) if kappa else 1.0
    a = _slope_step(camera) * (f_u * f_u * inv_x - eps) / (camera.mla_pitch_mm * pupil)
    return float(a) if np.ndim(a) == 0 else a
