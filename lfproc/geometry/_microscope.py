"""A light-field microscope's own geometry: z per a, the aperture's views, aplanatic per-view shifts.

Its slices are the generic ray model's (:mod:`._slices`) and its views the objective's own placement
(:meth:`lfproc.camera.Microscope.place_views`, the sine condition); this module holds what only an objective
has. Positions are micrometres from the native object plane.

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

import numpy as np

from ..errors import LfprocError
from ..camera import Microscope


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
    """dz/da = m̂·f_s·n/M² in µm, through the microscope's ray transfer (exact for the paraxial map,
    :meth:`lfproc.camera.Microscope.z_per_a_um`)."""
    return _scope(camera).z_per_a_um(camera)


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
    limit = min(max(scope.numerical_aperture / scope.immersion_index, float(radial[scope.inside_aperture(camera)].max())),
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
    w = (ux * ux + uy * uy) * _scope(camera).inside_aperture(camera)
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


def refocus_summary(camera) -> dict:
    """How this camera refocuses, for a report: with per-view gains (a microscope objective's sine condition)
    ``paraxial_depth_error`` and ``aplanatic`` (:func:`uses_aplanatic`); ``{}`` for optics that refocus with
    Eq. 9's shifts alone."""
    if _microscope_of(camera) is None:
        return {}
    return {"paraxial_depth_error": paraxial_depth_error(camera), "aplanatic": uses_aplanatic(camera)}
