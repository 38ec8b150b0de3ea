"""Which views a slice averages, seen as an aperture: its extent for the DOF and its equivalent f-number.

View offset i looks through the entrance pupil at F_i = i·ΔB (Eq. 17, ΔB the baseline of Eq. 34) and
its pixel spans one view step, ΔB wide, about it. A set of views whose offsets reach ±r along a lattice
axis therefore fills a pupil (2r + 1)·ΔB wide along it, and its equivalent f-number is

    N_eq = f_U / ((2r + 1)·ΔB) = f_s / ((2r + 1)·p_p)    (telecentric; ÷ |1 − ε/d_A| in ΔB otherwise).

For the full micro image (2c + 1 = m̂) that is f_s over the micro image pitch, the micro lenses'
f-number, which the main lens matches on a well-designed camera: the full set is the main lens's own
aperture. A synthetic aperture f/F keeps the views whose virtual centre lies inside a disc of diameter
f_U/F, the rule :func:`~lfproc.geometry.views_inside_aperture` applies to the main lens stop, so
f/N_main keeps exactly the views inside the main lens. Its DOF (Eqs. 24–31 with r for c, see
:mod:`._slices`) follows from the extent of what it keeps, and so does the f-number it is tagged with.
"""

from __future__ import annotations

import math

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._views import baseline_mm, view_positions_mm


def summed_view_extent(view_mask) -> int:
    """r: the largest offset |i_y| or |i_x| of the views that ``view_mask`` marks (``(m̂, m̂)`` booleans).

    The half-extent of the summed views along the lattice axes, what the DOF's c stands for
    (:func:`~lfproc.geometry.slice_geometry`'s ``view_extent``).
    """
    mask = np.asarray(view_mask, dtype=bool)
    if mask.ndim != 2 or mask.shape[0] != mask.shape[1] or mask.shape[0] % 2 == 0 or not mask.any():
        raise LfprocError(f"a view mask must be m x m booleans (m odd) marking at least one view, got shape "
                          f"{mask.shape}")
    c = (mask.shape[0] - 1) // 2
    rows, cols = np.nonzero(mask)
    return int(max(np.abs(rows - c).max(), np.abs(cols - c).max()))


def equivalent_f_number(camera: Camera, view_extent=None) -> float:
    """N_eq = f_U / ((2r + 1)·ΔB): the f-number of views reaching ±r along an axis (module docstring).

    ``None`` is the full micro image (r = c).
    """
    r = camera.center_index if view_extent is None else int(view_extent)
    return camera.main_focal_length_mm / ((2 * r + 1) * baseline_mm(camera, 1))


def aperture_limits(camera: Camera) -> tuple[float, float]:
    """(widest, narrowest) synthetic aperture f-numbers of ``camera``.

    The widest is the main lens's f-number (or, without one, the full micro image's); the narrowest
    is one view, f_U/ΔB.
    """
    widest = camera.f_number if camera.f_number is not None else equivalent_f_number(camera)
    return float(widest), camera.main_focal_length_mm / baseline_mm(camera, 1)


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
        raise LfprocError(f"--aperture {f_number!r} is not an f-number; give one from f/{widest:.3g} to "
                          f"f/{narrowest:.3g}, e.g. --aperture {min(max(2 * widest, 4.0), narrowest):g}")
    if f < widest * (1.0 - 1e-9):
        raise LfprocError(f"--aperture {f:g} is wider than the main lens (f/{widest:.3g}); give f/{widest:.3g} "
                          f"or narrower (up to f/{narrowest:.3g}, one view)")
    if f > narrowest * (1.0 + 1e-9):
        raise LfprocError(f"--aperture {f:g} is narrower than one view (f/{narrowest:.3g} on this camera); give "
                          f"f/{widest:.3g} to f/{narrowest:.3g}")
    pos = view_positions_mm(camera)
    radius = camera.main_focal_length_mm / (2.0 * f)
    r2 = pos[:, None] ** 2 + pos[None, :] ** 2
    return r2 <= radius * radius * (1.0 + 1e-12)
