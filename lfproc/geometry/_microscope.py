"""Slices and views of a light-field microscope in object space: micrometres from the native object plane.

The ray model of :mod:`._slices` with the microscope's transfer (:mod:`._transfer`): a ray pair (A, C)
meeting w = A·p_m/δ = A·m̂·f_s behind the MLA (δ = p_p/f_s, p_p = p_m/m̂) is the object point
s = n·w/M² in front of the native object plane, so slice a sits at

    z = a·m̂·f_s·n / M²          (f_s in µm: z in µm; the relay does not enter, m̂ counts the
                                  resampled samples per lens, each p_m/m̂ wide at the lenslet focus)

positive towards the objective (a > 0 refocuses nearer the objective, as nearer the camera in the
paper). The lateral sampling is one lens, p_m/M in the object (Levoy et al., "Light Field Microscopy",
SIGGRAPH 2006: one output pixel per lenslet).

Depth of field: the paper's border-ray pairs (Eqs. 23–31) with the views the objective fills, i.e.
those whose image-side ray sine is at most NA/M (c_NA views each side of the centre), plus the wave
term λ·n/NA² of the microscope's DOF, D_tot = λ·n/NA² + n·e/(M·NA) (Inoué and Spring, as Levoy et al.
use it; e the smallest distance the detector resolves in the image plane). For a lenslet f-number
matched to the objective the geometric part tends to n·p_m/(M·NA), the second term with e = p_m; with
m̂ = N_u samples per lens (N_u = p_m/R_obj, R_obj = 0.47·λ·M/NA) the DOF is within 8 % of Levoy et
al.'s (2 + N_u)·λ·n/(2·NA²). N_u central DOFs span |a| ≤ 1, the range over which one view stays sharp.
What was verified against which source is listed in docs/microscope.md.

Aplanatic refocusing. An objective obeys the Abbe sine condition, n·sin θ = M·sin θ'. View (ky, kx)
samples the image-side direction (u_x, u_y, f_s) with u = (k − c)·p_p, so in the object its ray has
direction sines (α, β) = M·(u_x, u_y)/(n·ρ), ρ = |(u_x, u_y, f_s)|, and cosine γ. A plane at depth z
displaces that ray laterally by z·(α, β)/γ, i.e. by M·z·(α, β)/(γ·p_m) lenses at the MLA. Written as
a·g·(c − k) with the z(a) above, the per-view multiplier is g = f_s/(ρ·γ) ≥ 1 (g = 1 paraxially):
with these shifts slice a is exactly the plane z(a). Paraxial shifts a·(c − k) instead focus view k at
z(a)/g_k: a point at depth z is sharpest (least squares over the views inside the NA, weights
w = |k − c|², as the spread across the views behind a lens) in the paraxial slice a = (z/z(1))·Σw·g/Σw,
so the paraxial tag z(a) overstates its depth by the fraction e = Σw·g/Σw − 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError
from ..camera import Microscope

UM_PER_MM = 1000.0


def _microscope_of(camera) -> Microscope | None:
    """The camera's main optics where they are an objective + tube lens (this module's own model), else None."""
    optics = getattr(camera, "main_optics", None)
    return optics if isinstance(optics, Microscope) else None


def _scope(camera) -> Microscope:
    scope = _microscope_of(camera)
    if scope is None:
        raise LfprocError(f"{getattr(camera, 'source', '') or 'camera'}: micrometre depths need a microscope camera "
                          f"([microscope] table); this camera has a main lens")
    return scope


def z_per_a_um(camera) -> float:
    """dz/da = m̂·f_s·n/M² in µm, through the microscope's ray transfer (exact for the paraxial map)."""
    # slice a's ray pair: a lenses apart, slopes one view step δ = p_p/f_s apart (w = a·m̂·f_s); the optics'
    # own object_position, so that slice_geometry's z is exactly a · z_per_a_um
    return float(_scope(camera).object_position(1.0, camera.mla_pitch_mm,
                                                camera.sample_pitch_mm / camera.mla_focal_length_mm))


def lateral_sampling_um(camera) -> float:
    """Object-space spacing of the lenses, p_m/M in µm (Levoy et al. 2006: one output pixel per lenslet)."""
    return camera.mla_pitch_mm / _scope(camera).objective_magnification * UM_PER_MM


def image_sines(camera, centre: float = 0.0):
    """Image-side direction sines of the views along one axis, i = −c…c, sampled at (i + ``centre``)·p_p
    under their lens (``centre``: where the decoder read the central view, in samples off the lens centre:
    the lit disc's centre, :attr:`lfproc.LightField.view_centre`)."""
    c = camera.center_index
    u = (np.arange(-c, c + 1) + float(centre)) * camera.sample_pitch_mm
    return u / np.hypot(u, camera.mla_focal_length_mm)


def pupil_positions_mm(camera, centre: float = 0.0) -> np.ndarray:
    """Where each view offset i = −c…c crosses the objective's back focal plane (its pupil), in mm: a
    microscope view's ``position_mm``, as F_i (Eq. 17) is a camera's. By the sine condition a ray leaving the
    sample at n·sin θ crosses it at f_obj·n·sin θ (f_obj = f_tube / M), which is −f_tube times the view's
    image-side sine; the sign follows the view's object-space angle. ``centre``: see :func:`image_sines`."""
    return -_scope(camera).tube_lens_focal_length_mm * image_sines(camera, centre) + 0.0


def object_numerical_aperture(camera, image_f_number: float) -> float:
    """The object-side NA of an image-side cone f/``image_f_number`` at the MLA: M/(2·N) by the Abbe sine
    condition (paraxial, NA_image = 1/(2·N)), at most the objective's NA (views outside it carry no light)."""
    scope = _scope(camera)
    na = scope.objective_magnification / (2.0 * image_f_number)
    return float(min(na, scope.numerical_aperture))


def na_views(camera) -> int:
    """c_NA: the largest view offset |i| whose image-side ray sine is within the objective's NA/M (≤ c)."""
    return _scope(camera).na_view_extent(camera.sample_pitch_mm, camera.mla_focal_length_mm, camera.center_index)


def _view_grid(camera, centre=(0.0, 0.0)):
    """(u_x, u_y, ρ) on the (m̂, m̂) view grid: image-side offsets under the lens and ρ = |(u_x, u_y, f_s)|;
    ``centre`` (c_y, c_x): where the central view was read, in samples off the lens centre."""
    c = camera.center_index
    k = np.arange(-c, c + 1, dtype=np.float64)
    p = camera.sample_pitch_mm
    ux, uy = np.meshgrid((k + float(centre[1])) * p, (k + float(centre[0])) * p)
    return ux, uy, np.sqrt(ux * ux + uy * uy + camera.mla_focal_length_mm ** 2)


def views_inside_na(camera) -> np.ndarray:
    """Boolean (m̂, m̂): views whose image-side ray sine is within NA/M (the objective's aperture)."""
    ux, uy, rho = _view_grid(camera)
    limit = _scope(camera).image_numerical_aperture
    return (ux * ux + uy * uy) <= (limit * rho) ** 2 * (1.0 + 1e-12)


def _view_directions(camera, centre=(0.0, 0.0)):
    """(α, β, γ, ρ) on the (m̂, m̂) view grid: object-space direction sines, cosine, and |(u, f_s)|.

    Views outside the objective's NA carry no light; their sines are clipped to the NA so γ stays real
    (around an off-centre disc, ``centre``, to the largest sine of the views inside it: those are exact).
    """
    scope = _scope(camera)
    ux, uy, rho = _view_grid(camera, centre)
    scale = scope.objective_magnification / (scope.immersion_index * rho)
    alpha, beta = ux * scale, uy * scale
    radial = np.hypot(alpha, beta)
    limit = min(max(scope.numerical_aperture / scope.immersion_index, float(radial[views_inside_na(camera)].max())),
                1.0 - 1e-9)
    clip = np.where(radial > limit, limit / np.where(radial > 0, radial, 1.0), 1.0)
    alpha, beta = alpha * clip, beta * clip
    gamma = np.sqrt(1.0 - alpha * alpha - beta * beta)
    return alpha, beta, gamma, rho


def aplanatic_gain(camera, centre=(0.0, 0.0)) -> np.ndarray:
    """g = f_s/(ρ·γ) per view (m̂, m̂): the sine condition's shift of view k over the paraxial a·(c − k)
    (``centre``: see :func:`refocus_slopes`)."""
    _, _, gamma, rho = _view_directions(camera, centre)
    return camera.mla_focal_length_mm / (rho * gamma)


def paraxial_depth_error(camera) -> float:
    """e = Σw·g/Σw − 1: the fraction by which a paraxial slice's z overstates the depth sharp in it (docstring)."""
    g = aplanatic_gain(camera)
    ux, uy, _ = _view_grid(camera)
    w = (ux * ux + uy * uy) * views_inside_na(camera)
    if not w.any():
        return 0.0
    return float((w * g).sum() / w.sum() - 1.0)


def uses_aplanatic(camera) -> bool:
    """Whether refocusing uses the sine condition's shifts: the camera file's ``aplanatic``, else automatic.

    Automatic: on where the paraxial map misses by more than a slice's DOF within the N_u resolvable
    depths (|a| ≤ 1, Levoy et al. 2006): a point at z(1) is sharpest in the paraxial slice tagged
    z(1)·(1 + e), on where e·z(1) > dof(1).
    """
    scope = _scope(camera)
    if scope.aplanatic is not None:
        return bool(scope.aplanatic)
    return paraxial_depth_error(camera) * z_per_a_um(camera) > float(microscope_slices(camera, 1.0).dof_um)


def refocus_slopes(camera, aplanatic: bool | None = None, centre=None):
    """Per-view shift multipliers (σ_y, σ_x), each (m̂, m̂): view (ky, kx) moves a·σ lenses in slice a.

    Paraxially σ = (c − ky, c − kx) (Eq. 9, centred); aplanatic σ = g·(c − k) (module docstring).
    ``aplanatic=None`` follows :func:`uses_aplanatic`. Returns ``None`` for a photographic camera or a
    paraxial microscope, meaning the refocus kernel's own a·(c − k). ``centre`` (c_y, c_x): where the
    decoder read the central view, in samples off the lens centre (the lit disc's centre): view k then
    sits at u = (k − c + centre)·p_p and its shift is that of u less that of the central view, so that
    the central view stays put and z(a) is unchanged (paraxially the table is still c − k).
    """
    if _microscope_of(camera) is None:
        return None
    if not (uses_aplanatic(camera) if aplanatic is None else aplanatic):
        return None
    c = camera.center_index
    base = (c - np.arange(camera.m_hat)).astype(np.float64)
    cy, cx = (0.0, 0.0) if centre is None else (float(centre[0]), float(centre[1]))
    g = aplanatic_gain(camera, (cy, cx))
    sy, sx = g * (base[:, None] - cy), g * (base[None, :] - cx)   # −g·u/p_p per view
    return sy - sy[c, c], sx - sx[c, c]


def microscope_slices(camera, a, view_extent=None):
    """z, DOF limits and DOF of slices ``a`` in µm: :func:`~._slices.slice_geometry` of a microscope camera.

    ``near`` (``z_near_um``) is the limit nearer the objective (the larger z), ``far`` (``z_far_um``) the one
    farther from it; ``dof = near − far`` = geometric DOF + λ·n/NA², the wave term split evenly. The
    geometric part is that of the views inside the NA, or of the views summed (``view_extent``) where given.
    """
    from ._slices import slice_geometry
    _scope(camera)
    return slice_geometry(camera, a, view_extent)


def refocus_parameter_z(camera, z_um) -> np.ndarray | float:
    """The ``a`` of the slice at ``z_um`` (µm from the native object plane, positive towards the objective)."""
    z = np.asarray(z_um, dtype=np.float64)
    if not np.all(np.isfinite(z)):
        raise LfprocError(f"depth {z_um} um is not a finite number of micrometres")
    a = z / z_per_a_um(camera)
    return float(a) if a.ndim == 0 else a


@dataclass(frozen=True, eq=False)
class MicroscopeViews:
    """Views of a microscope along one axis: offsets i = −c…c, object-space angle θ_i (°), inside the NA.

    The views are orthographic (the microscope is object-side telecentric): view i looks along θ_i,
    sin θ_i = M·sin θ'_i / n (Abbe sine condition), θ'_i the image-side angle atan(i·p_p/f_s).
    """

    i: np.ndarray
    angle_deg: np.ndarray
    inside_na: np.ndarray
    lateral_sampling_um: float

    def records(self) -> list[dict]:
        return [dict(i=int(i), angle_deg=(float(t) if math.isfinite(t) else None), inside_na=bool(k))
                for i, t, k in zip(self.i, self.angle_deg, self.inside_na)]


def microscope_views(camera, centre: float = 0.0) -> MicroscopeViews:
    """Object-space angles of the views (sine condition) and which lie inside the objective's NA.

    ``centre``: where the decoder read the central view along this axis, in samples off the lens centre
    (the lit disc's centre, :attr:`lfproc.LightField.view_centre`): the angles are those of the rays the
    views were read at. The NA is the disc's, so which views lie inside it does not change."""
    scope = _scope(camera)
    c = camera.center_index
    sines = -scope.objective_magnification * image_sines(camera, centre) / scope.immersion_index   # m_i = −i·p_p/f_s
    with np.errstate(invalid="ignore"):
        angle = np.degrees(np.arcsin(np.where(np.abs(sines) <= 1.0, sines, np.nan))) + 0.0
    inside = np.abs(np.arange(-c, c + 1)) <= na_views(camera)
    return MicroscopeViews(np.arange(-c, c + 1), angle, inside, lateral_sampling_um(camera))


def _a_for_lower_limit(camera, lower_um: float) -> float:
    """The ``a`` whose lower DOF limit (``z_far_um``) is ``lower_um``: inverts :func:`microscope_slices`.

    The far border-ray pair is A = (2ac − 1)/(2c + 1) where A ≥ 0 and (2ac − 1)/(2c − 1) below
    (c = c_NA, :func:`._slices._dof_pairs`), and z_far = z(A) − λn/(2NA²).
    """
    c = max(na_views(camera), 1)
    wave = _scope(camera).wave_depth_of_field()
    big_a = (lower_um + 0.5 * wave) / z_per_a_um(camera)
    return (big_a * (2 * c + 1) + 1.0) / (2 * c) if big_a >= 0 else (big_a * (2 * c - 1) + 1.0) / (2 * c)


def plan_z_range(camera, z0_um: float, z1_um: float, step_um: float | None = None,
                 max_slices: int = 10000) -> np.ndarray:
    """Slices for a depth range of a microscope, in µm from the native object plane (``--z-range``).

    Without ``step_um``: the fewest slices whose DOF intervals [z_far, z_near] together cover
    [z0, z1] (greedy from the far end, as :func:`plan_slices` for ``--depth-range``; neighbours overlap
    by 1e-9 relative against rounding). With ``step_um``: slices at z0, z0 + step, … up to z1 (an
    evenly spaced z-stack). Returns increasing ``a``.
    """
    lo, hi = float(min(z0_um, z1_um)), float(max(z0_um, z1_um))
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise LfprocError(f"z_range_um={z0_um}:{z1_um} must be finite micrometres, e.g. -50:50")
    zeta = z_per_a_um(camera)
    if step_um is not None:
        if not (math.isfinite(step_um) and step_um > 0):
            raise LfprocError(f"z_range_um= step must be a positive number of micrometres, got {step_um}")
        count = int(math.floor((hi - lo) / step_um + 1e-9)) + 1
        if count > max_slices:
            raise LfprocError(f"z_range_um={z0_um}:{z1_um}:{step_um} asks for {count} slices, more than {max_slices}; "
                              f"use a larger STEP")
        return (lo + step_um * np.arange(count)) / zeta
    slices, edge = [], lo
    while True:
        a = _a_for_lower_limit(camera, edge - 1e-9 * max(1.0, abs(edge)))
        slices.append(a)
        edge = float(microscope_slices(camera, a).z_near_um)
        if edge >= hi:
            return np.array(slices)
        if len(slices) >= max_slices:
            raise LfprocError(f"z_range_um={z0_um}:{z1_um} needs more than {max_slices} slices; narrow it")


#: a z step finer than the depth of field by more than this factor earns a warning (``z_step_advice``)
FINE_STEP_FACTOR = 10.0


def z_step_advice(camera, step_um: float, z0_um: float, z1_um: float) -> str | None:
    """A warning's text when an evenly spaced z-stack's step is far finer than the slices' depth of field.

    Slices a small fraction of their DOF apart show the same thing again (25 µm of DOF sampled every
    0.2 µm repeats each slice a hundred times, issue 32). Returns ``None`` unless ``step_um`` is more than
    :data:`FINE_STEP_FACTOR` times finer than the thinnest DOF over [z0, z1] (all views summed, the
    thinnest they can be); the text names a sensible step, half that DOF (neighbours overlap by half,
    so every depth is in focus in two slices).
    """
    lo, hi = float(min(z0_um, z1_um)), float(max(z0_um, z1_um))
    ends = microscope_slices(camera, np.array([lo, hi]) / z_per_a_um(camera))
    dof = float(np.min(ends.dof_um))
    if not (math.isfinite(dof) and dof > 0 and step_um * FINE_STEP_FACTOR < dof):
        return None
    return (f"a z step of {step_um:.4g} µm is {dof / step_um:.0f}x finer than the slices' depth of field "
            f"({dof:.3g} µm): neighbouring slices show the same; a step of about {dof / 2:.2g} µm (half the DOF) "
            f"samples the depth fully")
