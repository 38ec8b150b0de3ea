"""Which views a slice averages, seen as an aperture: its extent for the DOF and its equivalent f-number.

View offset i looks through the entrance pupil at F_i = i·ΔB (Eq. 17, ΔB the baseline of Eq. 34) and
its pixel spans one view step, ΔB wide, about it: a set of summed views is a pupil made of those
ΔB-wide cells. A point off the refocused slice (by Δa) blurs into a copy of that set Δa lenses per
view step; how fast the slice loses sharpness with Δa follows the copy's second moment along an axis.

Extent (the DOF's c). The paper's full micro image is the square set −c … c, whose pupil (views and
pixel widths) has the variance (2c + 1)²/12 along an axis. Any other set with the variance
σ² = Var(i) + 1/12 (the larger of the two axes) is given the extent of the square with the same
spread, r = (√(12σ²) − 1)/2 = (√(12·Var(i) + 1) − 1)/2, and the DOF formulas take r for c (see
:mod:`._slices`). The full square gives c exactly. A set of views within the 3 × 3 around the centre
counts as r = 1 (the formulas need r ≥ 1 once a neighbour is summed), the central view alone as r = 0.
On renders this keeps the measured sharpness width over the tagged DOF within ±15 % between the
full aperture, synthetic apertures and sets with dropped rims, where the outermost view alone does
not (``docs/aperture.md``).

Equivalent f-number. The disc with the same second moment, σ² = D²/16 (in ΔB units), has the
diameter D = 4σ·ΔB = (2r + 1)·ΔB·2/√3, so N_eq = f_U/D. A synthetic aperture f/F keeps the views whose
virtual centre lies inside a disc of diameter f_U/F (the rule
:func:`~lfproc.geometry.views_inside_aperture` applies to the main lens stop, so f/N_main keeps
exactly the views inside the main lens); its N_eq is F up to the view grid's granularity (f/4 → 3.75
on a 13-px Lytro-like micro image).
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import Camera
from ..errors import LfprocError


def summed_view_extent(view_mask) -> float:
    """r: the extent of the views that ``view_mask`` marks (``(m̂, m̂)`` booleans), as the DOF's c.

    The half-width of the square set of views with the same spread along a lattice axis (module
    docstring): c for the full set (and for ``None``), 0 for one view, at least 1 otherwise.

    Parameters
    ----------
    view_mask : ndarray (m̂, m̂) bool or None
        The views summed (``None``: all).

    Returns
    -------
    float
        r, in views (c for all of them).
    """
    mask = np.asarray(view_mask, dtype=bool)
    if mask.ndim != 2 or mask.shape[0] != mask.shape[1] or mask.shape[0] % 2 == 0 or not mask.any():
        raise LfprocError(f"a view mask must be m x m booleans (m odd) marking at least one view, got shape "
                          f"{mask.shape}")
    if mask.all():
        return float((mask.shape[0] - 1) // 2)
    rows, cols = np.nonzero(mask)
    variance = max(float(np.var(rows)), float(np.var(cols)))
    if variance == 0.0:
        return 0.0
    return max(1.0, (math.sqrt(12.0 * variance + 1.0) - 1.0) / 2.0)


def _pupil(camera: Camera):
    """The views as cells of a pupil (:meth:`lfproc.camera.MainOptics.view_pupil`): (coordinates (m̂,), the cell
    width, the length F divides into the diameter, the widest f-number or None).

    A camera's views sit at F_i = i·ΔB in the entrance pupil (Eq. 17), F = f_U / diameter. Orthographic
    views (a microscope's) are directions, with no position in a pupil: they are image-side ray slopes under
    the lenslets, i·p/f_s (p the sample pitch), and F = 1 / diameter in slope: the image-side working
    f-number, 1/(2·sine) for the optics' whole aperture (M/(2·NA) of an objective).
    """
    pupil = camera.main_optics.view_pupil(camera)
    return pupil.coordinates, pupil.cell, pupil.length, pupil.widest


def equivalent_f_number(camera: Camera, view_extent=None) -> float:
    """N_eq = f_U·√3 / (2·(2r + 1)·ΔB): the f-number of the disc as spread as views of extent r (module docstring).

    ``None`` is the full micro image (r = c). A microscope's is image-side (:func:`_pupil`).
    """
    r = camera.center_index if view_extent is None else float(view_extent)
    _, cell, length, _ = _pupil(camera)
    return length * math.sqrt(3.0) / (2.0 * (2.0 * r + 1.0) * cell)


def aperture_limits(camera: Camera) -> tuple[float, float]:
    """(widest, narrowest) synthetic aperture f-numbers of ``camera``.

    The widest is the main lens's f-number (a microscope objective's image-side M/(2·NA); without one, the
    full micro image's); the narrowest is one view, f_U/ΔB.
    """
    _, cell, length, widest = _pupil(camera)
    widest = widest if widest is not None else equivalent_f_number(camera)
    return float(widest), length / cell


def aperture_views(camera: Camera, f_number: float) -> np.ndarray:
    """``(m̂, m̂)`` booleans: the views whose virtual centre lies inside a synthetic aperture f/``f_number``.

    The aperture is a disc of diameter f_U/F in the entrance pupil (the module docstring); the central
    view is always inside.

    Raises
    ------
    LfprocError
        For an f-number that is not a finite number, wider than the main lens's (more light than the
        camera has) or narrower than one view (no view is that narrow).
    """
    try:
        f = float(f_number)
    except (TypeError, ValueError):
        f = math.nan
    widest, narrowest = aperture_limits(camera)
    if not math.isfinite(f) or f <= 0:
        raise LfprocError(f"`aperture={f_number!r}` is not an f-number; give one from f/{widest:.3g} to "
                          f"f/{narrowest:.3g}, e.g. `aperture={min(max(2 * widest, 4.0), narrowest):g}`")
    if f < widest * (1.0 - 1e-9):
        raise LfprocError(f"`aperture={f:g}` is wider than the main lens (f/{widest:.3g}); give f/{widest:.3g} "
                          f"or narrower (up to f/{narrowest:.3g}, one view)")
    if f > narrowest * (1.0 + 1e-9):
        raise LfprocError(f"`aperture={f:g}` is narrower than one view (f/{narrowest:.3g} on this camera); give "
                          f"f/{widest:.3g} to f/{narrowest:.3g}")
    pos, _, length, _ = _pupil(camera)
    radius = length / (2.0 * f)
    r2 = pos[:, None] ** 2 + pos[None, :] ** 2
    return r2 <= radius * radius * (1.0 + 1e-12)


def equivalent_numerical_aperture(camera: Camera, view_extent=None) -> float:
    """The summed views as an object-side NA: n·sin θ of their cone, M / (2·N_eq) by the Abbe sine condition
    (N_eq the image-side equivalent f-number, :func:`equivalent_f_number`; paraxial), at most the optics' own
    NA (views outside it carry no light). Microscopists think in NA, as photographers in f-numbers.

    Needs one lateral scale for every object point, i.e. optics with a lateral sampling (object-side
    telecentric, :meth:`lfproc.camera.MainOptics.lateral_sampling_um`): a lens's object-side cone changes with
    the object's distance.
    """
    optics = camera.main_optics
    sampling = optics.lateral_sampling_um(camera)
    if sampling is None:
        raise LfprocError(f"{camera.source or 'camera'}: an equivalent numerical aperture needs object-side "
                          f"telecentric optics (a microscope); this camera's summed views have an equivalent "
                          f"f-number (equivalent_f_number)")
    # the lateral magnification is the lens pitch over its footprint in the object; the widest cone is the stop's
    magnification = camera.mla_pitch_mm * 1000.0 / sampling
    return float(min(magnification / (2.0 * equivalent_f_number(camera, view_extent)),
                     magnification * optics.image_aperture_sine))


def aperture_text(camera: Camera, view_extent=None) -> str:
    """How people name the summed views' aperture: ``"f/5.6 equivalent"`` for a camera, ``"NA 0.42
    equivalent"`` for optics with one lateral scale (a microscope, :func:`equivalent_numerical_aperture`)."""
    if camera.main_optics.lateral_sampling_um(camera) is not None:   # object-side telecentric: one NA for every point
        return f"NA {equivalent_numerical_aperture(camera, view_extent):.2f} equivalent"
    return f"f/{equivalent_f_number(camera, view_extent):.2g} equivalent"
