"""Viewpoint images (the paper's Eq. 32) and the virtual camera behind each (Eqs. 17, 33, 34).

Eq. 32, E'_{u_{c+i}}[s_j] = E[u_{c+i}, s_j], gathers the pixel at the same micro image position
under every lens into one image: after decoding that is exactly ``lf.views[ky, kx]``. Each view
looks from a virtual optical centre F_i = m_i·f_U in the main lens's front focal plane (Eq. 17), with
its optical axis tilted by Φ_i (Eq. 33); adjacent views are ΔB_1 apart (Eq. 34). In two dimensions
view (ky, kx) has offsets (iy, ix) = (ky − c, kx − c) and the geometry applies per axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import geometry
from .errors import LfprocError
from .lightfield import LightField


def viewpoints(lf: LightField, *, inside_aperture: bool = False) -> np.ndarray:
    """The m̂ × m̂ viewpoint images of ``lf`` (Eq. 32), shaped ``(m̂, m̂, Ny, Nx, C)`` float32.

    Parameters
    ----------
    lf : LightField
    inside_aperture : bool
        If true, views whose virtual centre lies outside the main lens stop (vignetted corners,
        see :func:`lfproc.geometry.views_inside_aperture`) are set to 0; needs a camera with
        ``f_number``.

    Returns
    -------
    ndarray, shape (m̂, m̂, Ny, Nx, C)
        ``lf.views`` itself (no copy) unless ``inside_aperture`` masks some.
    """
    if not inside_aperture:
        return lf.views
    mask = aperture_mask(lf)
    return np.where(mask[:, :, None, None, None], lf.views, np.float32(0))


def aperture_mask(lf: LightField) -> np.ndarray:
    """``(m̂, m̂)`` booleans: views inside the main lens aperture (all true without an f-number)."""
    if lf.camera is None:
        raise LfprocError("the aperture of the views needs the light field's camera; decode with `camera=`")
    return geometry.views_inside_aperture(lf.camera)


def with_aperture(lf: LightField, f_number: float | None) -> LightField:
    """``lf`` with only the views inside a synthetic aperture f/``f_number`` marked (and the others 0).

    The views whose virtual centre lies inside a disc of diameter f_U/F in the entrance pupil
    (:func:`lfproc.geometry.aperture_views`), within those ``lf.view_mask`` already marks; refocusing
    the result averages only them, and its slices' DOF follows them
    (:func:`lfproc.geometry.summed_view_extent`). ``None`` returns ``lf`` unchanged.

    Raises
    ------
    LfprocError
        Without a camera, for an f-number wider than the main lens's or narrower than one view, or
        when no view that carries light is inside the aperture.

    Parameters
    ----------
    lf : LightField
        With its camera (a main lens's f-number).
    f_number : float or None
        The synthetic aperture's f-number, at least the main lens's.

    Returns
    -------
    LightField
        The same views with a narrower ``view_mask`` (``lf`` itself for ``None``).
    """
    if f_number is None:
        return lf
    if lf.camera is None:
        raise LfprocError("a synthetic aperture needs the light field's camera; decode with `camera=`")
    keep = geometry.aperture_views(lf.camera, f_number)
    if lf.view_mask is not None:
        keep = keep & lf.view_mask
    if not keep.any():
        raise LfprocError(f"no view that carries light lies inside f/{float(f_number):g}; give a wider "
                          f"`aperture=`")
    return LightField.from_views(lf.views, lf.camera, lf.grid, keep, lf.view_centre, lf.inputs)


@dataclass(frozen=True)
class ViewpointGeometry:
    """The virtual camera of view (ky, kx); lengths in mm, angles in degrees, pairs as [y, x].

    Orthographic views (a microscope's: the optics place them as directions, without a baseline):
    ``position_mm`` is where each crosses the objective's pupil, ``tilt_deg`` and ``angle_deg`` its object-space
    angle (sine condition, :func:`lfproc.geometry.place_views`), ``inside_na`` whether it lies inside the NA
    (:func:`lfproc.geometry.views_inside_aperture`); it has no baselines (``None``).
    """

    view: tuple            # (ky, kx)
    offset: tuple          # (iy, ix) = (ky − c, kx − c)
    position_mm: tuple | None     # (F_iy, F_ix), Eq. 17 (a microscope: in the objective's pupil)
    tilt_deg: tuple | None        # (Φ_iy, Φ_ix), Eq. 33
    baseline_to_center_mm: float | None   # |F_i − F_0| in the focal plane, Eq. 34 in 2-D
    baseline_to_neighbour_mm: float | None  # ΔB_1, Eq. 34 with g = 1
    angle_deg: tuple | None = None  # microscope: (θ_iy, θ_ix) in the object
    inside_na: bool | None = None   # microscope: the view lies inside the objective's NA

    def metadata(self) -> dict:
        """The contract's sidecar fields (plus the baselines); a microscope view's: ``position_mm`` in the
        objective's pupil, ``tilt_deg`` its object-space angle (also as ``angle_deg``) and ``inside_na``."""
        if self.angle_deg is not None:   # a microscope: position in the objective's pupil, tilt = the angle
            return {"view": list(self.view), "position_mm": list(self.position_mm), "tilt_deg": list(self.tilt_deg),
                    "angle_deg": list(self.angle_deg), "inside_na": self.inside_na}
        return {"view": list(self.view), "position_mm": list(self.position_mm), "tilt_deg": list(self.tilt_deg),
                "baseline_to_center_mm": self.baseline_to_center_mm,
                "baseline_to_neighbour_mm": self.baseline_to_neighbour_mm}


def viewpoint_geometry(camera, centre=None) -> list[list[ViewpointGeometry]]:
    """Virtual camera of every view as an m̂ × m̂ nested list indexed ``[ky][kx]``.

    ``centre`` (c_y, c_x): where the decoder read the central view, in samples off the lens centres
    (:attr:`lfproc.LightField.view_centre`, the lit disc's centre); the tags are those of the rays the
    views were read at, view k at offset k − c + centre. ``None``: at the lens centres.
    """
    offsets = geometry.view_offsets(camera)
    cy, cx = (0.0, 0.0) if centre is None else (float(centre[0]), float(centre[1]))
    along_y, along_x = geometry.place_views(camera, offsets + cy), geometry.place_views(camera, offsets + cx)
    if along_y.orthographic:   # views are directions: angles, positions in the objective's pupil
        inside = geometry.views_inside_aperture(camera)
        return [[ViewpointGeometry((ky, kx), (int(iy), int(ix)),
                                   (float(along_y.position_mm[ky]), float(along_x.position_mm[kx])),
                                   (_finite(along_y.tilt_deg[ky]), _finite(along_x.tilt_deg[kx])), None, None,
                                   angle_deg=(_finite(along_y.tilt_deg[ky]), _finite(along_x.tilt_deg[kx])),
                                   inside_na=bool(inside[ky, kx]))
                 for kx, ix in enumerate(offsets)] for ky, iy in enumerate(offsets)]
    neighbour = along_y.baseline_mm
    table = []
    for ky, iy in enumerate(offsets):
        row = []
        for kx, ix in enumerate(offsets):
            row.append(ViewpointGeometry(
                (ky, kx), (int(iy), int(ix)), (float(along_y.position_mm[ky]), float(along_x.position_mm[kx])),
                (float(along_y.tilt_deg[ky]), float(along_x.tilt_deg[kx])),
                float(math.hypot(along_y.position_mm[ky], along_x.position_mm[kx])), float(neighbour)))
        table.append(row)
    return table


def _finite(value) -> float | None:
    return float(value) if math.isfinite(value) else None


def mosaic(views: np.ndarray, gap: int = 0) -> np.ndarray:
    """Tile all views into one image: view (ky, kx) at block row ky, block column kx.

    Returns ``(m̂·Ny + (m̂−1)·gap, m̂·Nx + (m̂−1)·gap, C)`` float32 (gaps are 0); a block of views that is
    not square (a mosaic cropped to the rows and columns of the lit views) tiles its own rows and columns.
    """
    rows, cols, ny, nx, ch = views.shape
    out = np.zeros((rows * ny + (rows - 1) * gap, cols * nx + (cols - 1) * gap, ch), np.float32)
    for ky in range(rows):
        for kx in range(cols):
            y0, x0 = ky * (ny + gap), kx * (nx + gap)
            out[y0:y0 + ny, x0:x0 + nx] = views[ky, kx]
    return out


def circular_walk(m_hat: int, radius: float | None = None, frames: int = 24,
                  mask: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Views (ky, kx) visited by a walk around a circle of ``radius`` views about the centre.

    The default radius is 0.7·c, inside the aperture of a typical f-number-matched camera; with
    ``mask`` the radius shrinks until every visited view is inside it. Consecutive duplicates are
    dropped.
    """
    c = (m_hat - 1) // 2
    if c == 0:
        return [(0, 0)]
    r = 0.7 * c if radius is None else float(radius)
    while True:
        path = []
        for t in np.linspace(0, 2 * np.pi, frames, endpoint=False):
            k = (int(round(c + r * math.sin(t))), int(round(c + r * math.cos(t))))
            if not path or path[-1] != k:
                path.append(k)
        if mask is None or all(mask[k] for k in path) or r <= 0.5:
            return path
        r -= 0.5
