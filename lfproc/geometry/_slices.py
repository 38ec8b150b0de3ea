"""The paper's paraxial ray model: where each refocused slice is focused, and where each view looks from.

Pure, vectorised functions of a :class:`~lfproc.camera.Camera` and the refocus parameter ``a``; no
images. Every distance is measured from the sensor, in millimetres.

Closed forms
------------
Write p_m for the micro lens pitch, p_p = p_m / m̂ for the effective pixel pitch, f_s and f_U for the
focal lengths, b_U for the main lens–MLA spacing, ε = b_U − f_U ≥ 0, δ = p_p / f_s (the slope step
between adjacent micro image positions, Eq. 13) and L = f_s + H1sH2s + b_U + H1UH2U.

Central distance (Eqs. 13–21). The two chief rays that Eq. 9 merges for neighbouring views — pixel
i under lens j and pixel i + 1 under lens j − a — leave the main lens (Eq. 16) with a separation
a·p_m + δ·b_U and converge with a slope difference (a·p_m + δ·ε)/f_U (Eq. 18). They meet
(Eq. 20) at z_a = f_U + f_U²·δ / (a·p_m + δ·ε) from H1U, for every i and j, so (Eq. 21)

    d_a = L + f_U + f_U²·δ / (a·p_m + δ·ε).

This is Newton's form x·x' = f²: the second term is the object distance from the front focal
plane. It is exact at a = 0 (infinite when ε = 0) and loses no digits up to a = 1e4, which the
2×2 solve of Eq. 20 would.

Depth of field (Eqs. 23–31). The extreme pixels merged by Eq. 9 are i = −c under lens j + 2ac and
i = +c under lens j. Their *inner* border rays (pixel border towards the micro image centre, from
the far border of each micro lens, Eqs. 24–26) meet at d_a−, the *outer* ones at d_a+. Solving as
above, these are the central formula evaluated at shifted parameters:

    d_a− = d(a₋),  a₋ = (2ac + 1)/(2c − 1);     d_a+ = d(a₊),  a₊ = (2ac − 1)/(2c + 1).

Domain. The rays meet in front of the camera when a·p_m + δ·ε > 0 (the usual case, a above
a_∞ = −δ·ε/p_m, the slice at infinity). Between a_0 = −δ·b_U/p_m and a_∞ they diverge: the slice
is "beyond infinity" and its distance is ``inf``. Below a_0 they meet between the main lens and its
front focal plane (z < f_U), a macro regime the paraxial model still describes; distances there are
finite and below L + f_U. Distances are never negative and never NaN.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from .camera import Camera
from .errors import LfprocError

#: default wavelength for the Airy limit (Eq. 22), in millimetres (550 nm)
DEFAULT_WAVELENGTH_MM = 550e-6


def _slope_step(camera: Camera) -> float:
    """δ = p_p / f_s with the effective pixel pitch (Eq. 13 for Δu = 1)."""
    return camera.effective_pixel_pitch_mm / camera.mla_focal_length_mm


def _distance_at(camera: Camera, a) -> np.ndarray:
    """d(a) of the module docstring, vectorised; ``inf`` where the rays do not meet in front."""
    a = np.asarray(a, dtype=np.float64)
    f_u = camera.main_focal_length_mm
    eps = camera.image_distance_mm - f_u
    delta = _slope_step(camera)
    denom = a * camera.mla_pitch_mm + delta * eps
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        newton_x = f_u * f_u * delta / denom
        z = f_u + newton_x
    meets_in_front = (denom > 0) | ((denom < 0) & (z > 0))
    z = np.where(meets_in_front & np.isfinite(z), z, np.inf)
    return camera.sensor_to_main_lens_mm + z


def _dof_parameters(camera: Camera, a):
    """(a₋, a₊): the parameters whose central distance is the near and far DOF limit of slice a."""
    a = np.asarray(a, dtype=np.float64)
    c = camera.center_index
    if c == 0:  # m̂ = 1: a single pixel per lens; both borders of the one pixel bound the DOF
        return np.full_like(a, -1.0), np.full_like(a, -1.0)
    return (2.0 * a * c + 1.0) / (2.0 * c - 1.0), (2.0 * a * c - 1.0) / (2.0 * c + 1.0)


def slice_distance_mm(camera: Camera, a) -> np.ndarray | float:
    """Central distance d_a of refocused slice ``a`` from the sensor (Eqs. 13–21).

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
    """

    a: np.ndarray
    distance_mm: np.ndarray
    near_mm: np.ndarray
    far_mm: np.ndarray
    dof_mm: np.ndarray

    def records(self) -> list[dict]:
        """One dict per slice with the contract's JSON keys; infinity as ``math.inf``."""
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
        rays do not meet in front of the camera. For a < −1 the inner and outer rays swap roles
        (the paper only treats a ≥ 0); the limits are ordered regardless.
    """
    a_arr = np.asarray(a, dtype=np.float64)
    a_near, a_far = _dof_parameters(camera, a_arr)
    d = _distance_at(camera, a_arr)
    limit1, limit2 = _distance_at(camera, a_near), _distance_at(camera, a_far)
    near = np.minimum(np.minimum(limit1, limit2), d)
    far = np.maximum(np.maximum(limit1, limit2), d)
    # the interval [a₊, a₋] crossing the slice at infinity means the DOF reaches infinity
    a_inf = infinity_parameter(camera)
    crosses = (np.minimum(a_near, a_far) <= a_inf) & (np.maximum(a_near, a_far) > a_inf)
    far = np.where(crosses, np.inf, far)
    near = np.where(crosses, np.minimum(_distance_at(camera, np.maximum(a_near, a_far)), d), near)
    with np.errstate(invalid="ignore"):
        dof = np.where(np.isinf(far), np.inf, far - near)
    if a_arr.ndim == 0:
        return SliceGeometry(float(a_arr), float(d), float(near), float(far), float(dof))
    return SliceGeometry(a_arr, d, near, far, dof)


def infinity_parameter(camera: Camera) -> float:
    """a_∞ = −δ·(b_U − f_U)/p_m: the refocus parameter of the slice focused at infinity (0 when b_U = f_U)."""
    eps = camera.image_distance_mm - camera.main_focal_length_mm
    return -_slope_step(camera) * eps / camera.mla_pitch_mm


def refocus_parameter(camera: Camera, distance_mm) -> np.ndarray | float:
    """The ``a`` whose slice is centred at ``distance_mm`` from the sensor (inverse of Eq. 21).

    a = δ·(f_U² / x − ε) / p_m with x = d − L − f_U, the distance from the front focal plane.

    Raises
    ------
    LfprocError
        For a distance at or behind the main lens (d ≤ L), or NaN.
    """
    d = np.asarray(distance_mm, dtype=np.float64)
    inside = camera.sensor_to_main_lens_mm
    if np.any(np.isnan(d)) or np.any(d <= inside):
        bad = d[np.isnan(d) | (d <= inside)].ravel()[0]
        raise LfprocError(f"distance {bad} mm is not in front of the main lens (it must exceed {inside:.3f} mm "
                          f"from the sensor); give a larger distance")
    f_u = camera.main_focal_length_mm
    eps = camera.image_distance_mm - f_u
    x = d - inside - f_u
    with np.errstate(divide="ignore"):
        inv_x = np.where(np.isinf(d), 0.0, 1.0 / x)
    a = _slope_step(camera) * (f_u * f_u * inv_x - eps) / camera.mla_pitch_mm
    return float(a) if a.ndim == 0 else a


def _slice_for_far_limit(camera: Camera, far_mm: float) -> float:
    """The ``a`` whose far DOF limit equals ``far_mm`` (inverts a₊ = (2ac − 1)/(2c + 1), or a₋ below a = −1)."""
    c = camera.center_index
    a_limit = refocus_parameter(camera, far_mm)
    a = (a_limit * (2.0 * c + 1.0) + 1.0) / (2.0 * c)
    if a < -1.0:  # there the inner and outer rays swap roles: the far limit is d(a₋), a₋ = (2ac + 1)/(2c − 1)
        a = (a_limit * (2.0 * c - 1.0) - 1.0) / (2.0 * c)
    # Near infinity a₊ = (2ac − 1)/(2c + 1) cancels digits, so the far limit of that a can fall short
    # of far_mm (or stay finite for far_mm = inf). Lower a by doubling steps from the rounding of a₊
    # until it reaches: the far limit never increases with a, so this ends, overshooting by < 2 steps.
    step = 2.0 ** -52 * (abs(a) + 1.0 / (2.0 * c))
    for _ in range(2000):
        if slice_geometry(camera, a).far_mm >= far_mm:
            break
        a -= step
        step *= 2.0
    return a


def plan_slices(camera: Camera, near_mm: float, far_mm: float, *, max_gap_mm: float = 0.0, integer: bool = False,
                max_slices: int = 10000) -> np.ndarray:
    """The fewest refocus parameters whose [near, far] DOF intervals together cover [near_mm, far_mm].

    Greedy from the far end, which is optimal for intervals whose both ends decrease with ``a``:
    each slice is the one whose far limit sits exactly on the nearest point not yet covered, so its
    near limit reaches as close as any slice covering that point can. Neighbouring intervals touch
    (with a 1e-9 relative overlap against rounding), so no depth in the range is left out of focus.

    Two ways to compute less, when the scene allows:

    * ``max_gap_mm`` > 0 tolerates uncovered depths up to that size *between* slices (never at the
      ends of the range): the next slice's far limit may sit that much nearer, so fewer slices.
    * ``integer=True`` uses integer ``a`` only — pure gathers, no interpolation, the cheapest slices —
      and leaves the gaps between integer slices that the paper points out (Section 5.2). Where even
      the next integer cannot keep a gap within ``max_gap_mm`` it is taken anyway; check the result
      with :func:`uncovered_depths`.

    Parameters
    ----------
    camera : Camera
        Needs m̂ ≥ 3 (a single-pixel micro image cannot refocus).
    near_mm, far_mm : float
        The depth range from the sensor; ``far_mm`` may be ``inf``.
    max_gap_mm : float
        Largest uncovered depth interval allowed between slices.
    integer : bool
        Plan integer refocus parameters only.
    max_slices : int
        Guard against ranges that would need absurdly many slices.

    Returns
    -------
    ndarray of float
        Refocus parameters, far slice first (increasing ``a``).
    """
    if camera.center_index == 0:
        raise LfprocError("depth-range planning needs micro images of 3 px or more (micro_image_px >= 3)")
    if not (near_mm > 0 and far_mm >= near_mm) or math.isnan(far_mm):
        raise LfprocError(f"depth range {near_mm}:{far_mm} mm is not a valid range; give NEAR:FAR with 0 < NEAR <= FAR")
    if not (max_gap_mm >= 0 and math.isfinite(max_gap_mm)):
        raise LfprocError(f"the largest allowed DOF gap must be a finite number of mm >= 0, got {max_gap_mm}")
    closest = camera.sensor_to_main_lens_mm + camera.main_focal_length_mm
    if near_mm <= closest:
        raise LfprocError(f"depth range starts at {near_mm} mm, but slices of this camera focus only beyond "
                          f"{closest:.3f} mm from the sensor; give a larger NEAR")
    slices: list[float] = []
    edge = far_mm                   # everything beyond the edge is covered (or an allowed gap)
    target = far_mm * (1.0 + 1e-9)  # every target a hair beyond, so rounding never leaves a sliver uncovered
    while True:
        a = _slice_for_far_limit(camera, target)
        if integer:  # the largest integer whose far limit still reaches the target (far decreases with a)
            a = float(math.floor(a + 1e-9))
            if slices and a <= slices[-1]:
                a = slices[-1] + 1.0
            if float(slice_geometry(camera, a).near_mm) >= edge:
                a += 1.0  # its interval lies wholly beyond the edge: the next integer makes progress
        slices.append(a)
        reached = float(slice_geometry(camera, a).near_mm)
        if reached > edge and not integer:  # the DOF here is narrower than the 1e-9 overlap: no progress possible
            raise LfprocError(f"depth range {near_mm}:{far_mm} mm reaches within a rounding error of the nearest "
                              f"slice ({closest:.3f} mm), where slices are too thin to plan; give a larger NEAR")
        edge = min(edge, reached)
        if edge <= near_mm:
            break
        if len(slices) >= max_slices:
            raise LfprocError(f"depth range {near_mm}:{far_mm} mm needs more than {max_slices} slices; narrow it")
        target = max(edge - max_gap_mm, near_mm) * (1.0 + 1e-9)
    return np.array(slices)


def uncovered_depths(camera: Camera, a_values, near_mm: float, far_mm: float) -> list[tuple[float, float]]:
    """Depth intervals inside [near_mm, far_mm] that no slice's [near, far] DOF interval covers."""
    geo = slice_geometry(camera, np.atleast_1d(np.asarray(a_values, dtype=np.float64)))
    intervals = sorted(zip(np.atleast_1d(geo.near_mm), np.atleast_1d(geo.far_mm)))
    gaps, covered_to = [], near_mm
    for lo, hi in intervals:
        if lo > covered_to and covered_to < far_mm:
            gaps.append((float(covered_to), float(min(lo, far_mm))))
        covered_to = max(covered_to, hi)
    if covered_to < far_mm:
        gaps.append((float(covered_to), float(far_mm)))
    return gaps


def integer_slice_gaps(camera: Camera, a_values) -> list[tuple[float, float, float]]:
    """Depth gaps that no integer slice covers (the paper's Section 5.2 observation).

    Parameters
    ----------
    a_values : array_like of int
        Slices to inspect, e.g. ``range(0, 6)``.

    Returns
    -------
    list of (a, gap_near_mm, gap_far_mm)
        For each consecutive pair (a, a + 1) whose intervals do not touch, the uncovered depths
        between d_(a+1)+ and d_a−.
    """
    a_sorted = np.unique(np.asarray(a_values, dtype=np.float64))
    geo = slice_geometry(camera, a_sorted)
    gaps = []
    for k in range(len(a_sorted) - 1):
        if a_sorted[k + 1] != a_sorted[k] + 1:  # only neighbouring integer slices bound a gap between them
            continue
        nearer_far, farther_near = geo.far_mm[k + 1], geo.near_mm[k]
        if nearer_far < farther_near:
            gaps.append((float(a_sorted[k]), float(nearer_far), float(farther_near)))
    return gaps


# ---------------------------------------------------------------------------- virtual cameras (Section 4)
def view_offsets(camera: Camera) -> np.ndarray:
    """i = k − c for every view index k = 0 … m̂ − 1."""
    c = camera.center_index
    return np.arange(-c, c + 1)


def view_slopes(camera: Camera, i=None) -> np.ndarray:
    """Chief-ray slope m_i = −i·p_p/f_s of view offset i (Eq. 13 with Δu = −i)."""
    i = view_offsets(camera) if i is None else np.asarray(i, dtype=np.float64)
    return -i * _slope_step(camera) + 0.0  # + 0.0: the central view is at 0.0, not -0.0


def view_positions_mm(camera: Camera, i=None) -> np.ndarray:
    """Virtual optical centre F_i = m_i·f_U in the main lens focal plane (Eq. 17), per view offset i."""
    return view_slopes(camera, i) * camera.main_focal_length_mm


def view_tilts_deg(camera: Camera, i=None) -> np.ndarray:
    """Tilt Φ_i = arctan(m_i·(b_U − f_U)/f_U) of each virtual camera's optical axis (Eq. 33), in degrees.

    Zero for every view when b_U = f_U; otherwise the sign of F_i (the contract's convention; the
    paper's Table 4 prints the opposite sign for the same magnitudes).
    """
    eps = camera.image_distance_mm - camera.main_focal_length_mm
    tilt = np.degrees(np.arctan(view_slopes(camera, i) * eps / camera.main_focal_length_mm))
    return tilt + 0.0  # no negative zeros (b_U = f_U gives -0.0 for i > 0)


def baseline_mm(camera: Camera, gap=1) -> np.ndarray | float:
    """Baseline ΔB_g = |F_i − F_(i+g)| = g·p_p·f_U/f_s between views g apart (Eq. 34)."""
    b = np.abs(np.asarray(gap, dtype=np.float64)) * _slope_step(camera) * camera.main_focal_length_mm
    return float(b) if b.ndim == 0 else b


@dataclass(frozen=True, eq=False)
class ViewGeometry:
    """Virtual cameras of the views along one axis: offsets i = −c…c, positions F_i (mm), tilts Φ_i (°)."""

    i: np.ndarray
    position_mm: np.ndarray
    tilt_deg: np.ndarray
    baseline_mm: float

    def records(self) -> list[dict]:
        return [dict(i=int(i), position_mm=float(p), tilt_deg=float(t))
                for i, p, t in zip(self.i, self.position_mm, self.tilt_deg)]


def view_geometry(camera: Camera) -> ViewGeometry:
    """Positions, tilts and the adjacent baseline of all views (Eqs. 17, 33, 34)."""
    i = view_offsets(camera)
    return ViewGeometry(i, view_positions_mm(camera, i), view_tilts_deg(camera, i), baseline_mm(camera, 1))


def views_inside_aperture(camera: Camera) -> np.ndarray:
    """Boolean mask ``(m̂, m̂)`` of views whose virtual centre lies inside the main lens aperture.

    The virtual centre of view (ky, kx) sits at (F_iy, F_ix) in the front focal plane; with an
    image-side telecentric main lens the stop is there, of diameter f_U / N. Views outside it see
    no light (the dark corners of every micro image). Without ``f_number`` every view is kept.
    """
    m = camera.m_hat
    if camera.f_number is None:
        return np.ones((m, m), dtype=bool)
    pos = view_positions_mm(camera)
    radius = camera.main_focal_length_mm / (2.0 * camera.f_number)
    r2 = pos[:, None] ** 2 + pos[None, :] ** 2
    return r2 <= radius * radius * (1.0 + 1e-12)


# ---------------------------------------------------------------------------- diffraction (Eq. 22)
def airy_radius_mm(f_number, wavelength_mm: float = DEFAULT_WAVELENGTH_MM):
    """Radius of the Airy disk's central peak, (Δℓ)min ≈ 1.22·λ·f/A = 1.22·λ·N (Eq. 22)."""
    return 1.22 * wavelength_mm * np.asarray(f_number, dtype=np.float64)


@dataclass(frozen=True)
class DiffractionCheck:
    """Eq. 22 against the effective pixel pitch for the two apertures in the path.

    ``main_lens_airy_mm`` uses the main lens f-number (``None`` without one); ``micro_lens_airy_mm``
    the micro lenses' working f-number f_s / p_m, which sets the spot every collimated beam forms on
    the sensor. ``pixel_limited`` is true when both are at most the effective pixel pitch: then the
    pixels, as the model assumes, bound the depth of field.
    """

    wavelength_mm: float
    effective_pixel_pitch_mm: float
    main_lens_airy_mm: float | None
    micro_lens_airy_mm: float
    pixel_limited: bool

    def message(self) -> str:
        parts = [f"micro lens Airy radius {self.micro_lens_airy_mm * 1e3:.2f} um"]
        if self.main_lens_airy_mm is not None:
            parts.append(f"main lens Airy radius {self.main_lens_airy_mm * 1e3:.2f} um")
        verdict = ("pixel-limited, as the model assumes" if self.pixel_limited else
                   "diffraction-limited: the optics, not the pixels, bound the DOF, which is then wider than predicted")
        return (f"{', '.join(parts)} vs effective pixel pitch {self.effective_pixel_pitch_mm * 1e3:.2f} um at "
                f"{self.wavelength_mm * 1e6:.0f} nm: {verdict}")


def diffraction_check(camera: Camera, wavelength_mm: float = DEFAULT_WAVELENGTH_MM,
                      warn: bool = True) -> DiffractionCheck:
    """Compare the Airy limit (Eq. 22) with the effective pixel pitch; warn when diffraction dominates."""
    if not (wavelength_mm > 0 and math.isfinite(wavelength_mm)):
        raise LfprocError(f"wavelength must be a positive number of millimetres, got {wavelength_mm}")
    pitch = camera.effective_pixel_pitch_mm
    main = None if camera.f_number is None else float(airy_radius_mm(camera.f_number, wavelength_mm))
    micro = float(airy_radius_mm(camera.mla_focal_length_mm / camera.mla_pitch_mm, wavelength_mm))
    limited = micro <= pitch and (main is None or main <= pitch)
    check = DiffractionCheck(wavelength_mm, pitch, main, micro, limited)
    if warn and not limited:
        warnings.warn(check.message(), DiffractionWarning, stacklevel=2)
    return check


class DiffractionWarning(UserWarning):
    """The Airy disk exceeds the effective pixel pitch: predicted DOFs are lower bounds."""
