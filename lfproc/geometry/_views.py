"""Virtual cameras of the viewpoint images (Section 4: Eqs. 17, 33, 34; finite exit pupil: Hahne et al. 2018)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ._exit_pupil import pupil_curvature
from ._slices import _slope_step


def _virtual_cameras(camera: Camera) -> None:
    """Refuse orthographic views (a microscope's): they have object-space angles instead of virtual cameras."""
    if camera.main_optics.views_are_orthographic:   # object-side telecentric: every view is a direction, no pinhole
        camera.require_main_lens("virtual camera positions, tilts and baselines (a microscope's views are "
                                 "orthographic: see their object-space angles, lfproc.geometry.microscope_views)")


def _pupil_factor(camera: Camera) -> float:
    """1 − ε/d_A: the virtual cameras spread by 1/(1 − ε/d_A) with a finite exit pupil (exactly 1.0 telecentric)."""
    _virtual_cameras(camera)
    return 1.0 - pupil_curvature(camera) * (camera.image_distance_mm - camera.main_focal_length_mm)


def view_offsets(camera: Camera) -> np.ndarray:
    """i = k − c for every view index k = 0 … m̂ − 1."""
    c = camera.center_index
    return np.arange(-c, c + 1)


def view_slopes(camera: Camera, i=None) -> np.ndarray:
    """Chief-ray slope m_i = −i·p_p/f_s of view offset i under the lens on the optical axis (Eq. 13, Δu = −i)."""
    i = view_offsets(camera) if i is None else np.asarray(i, dtype=np.float64)
    return -i * _slope_step(camera) + 0.0  # + 0.0: the central view is at 0.0, not -0.0


def view_positions_mm(camera: Camera, i=None) -> np.ndarray:
    """Lateral position of each view's virtual optical centre: F_i = m_i·f_U (Eq. 17), per view offset i.

    With a finite exit pupil the centres lie in the entrance pupil plane
    (:func:`~lfproc.geometry.virtual_camera_plane_mm`) at m_i·f_U/(1 − ε/d_A) (Hahne et al. 2018).
    """
    _virtual_cameras(camera)
    return view_slopes(camera, i) * camera.main_focal_length_mm / _pupil_factor(camera)


def view_tilts_deg(camera: Camera, i=None) -> np.ndarray:
    """Tilt Φ_i = arctan(m_i·(b_U − f_U)/f_U) of each virtual camera's optical axis (Eq. 33), in degrees.

    Zero for every view when b_U = f_U; otherwise the sign of F_i (the contract's convention; the
    paper's Table 4 prints the opposite sign for the same magnitudes). The axis is the view's ray
    through the lens on the optical axis, so a finite exit pupil leaves the tilt unchanged.
    """
    _virtual_cameras(camera)
    eps = camera.image_distance_mm - camera.main_focal_length_mm
    tilt = np.degrees(np.arctan(view_slopes(camera, i) * eps / camera.main_focal_length_mm))
    return tilt + 0.0  # no negative zeros (b_U = f_U gives -0.0 for i > 0)


def baseline_mm(camera: Camera, gap=1) -> np.ndarray | float:
    """Baseline ΔB_g = |F_i − F_(i+g)| = g·p_p·f_U/f_s between views g apart (Eq. 34; ÷ |1 − ε/d_A| with d_A)."""
    _virtual_cameras(camera)
    b = np.abs(np.asarray(gap, dtype=np.float64)) * _slope_step(camera) * camera.main_focal_length_mm
    b = b / abs(_pupil_factor(camera))
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

    The virtual centre of view (ky, kx) sits at (F_iy, F_ix) in the entrance pupil (the front focal
    plane for an image-side telecentric main lens), whose diameter is f_U / N. Views outside it see
    no light (the dark corners of every micro image). Without ``f_number`` every view is kept.

    Orthographic views (a microscope's) are directions, not positions in a pupil: those whose image-side
    ray sine is within the optics' :attr:`~lfproc.camera.MainOptics.image_aperture_sine`, NA/M
    (:func:`~._microscope.views_inside_na`).
    """
    m = camera.m_hat
    optics = camera.main_optics
    if optics.views_are_orthographic:    # views are directions: the stop bounds their sine (Abbe), not a position
        from ._microscope import views_inside_na
        return views_inside_na(camera)
    if optics.image_aperture_sine is None:
        return np.ones((m, m), dtype=bool)
    pos = view_positions_mm(camera)
    radius = camera.main_focal_length_mm / (2.0 * camera.f_number)
    r2 = pos[:, None] ** 2 + pos[None, :] ** 2
    return r2 <= radius * radius * (1.0 + 1e-12)
