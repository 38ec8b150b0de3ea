"""Where the views look from (Section 4: Eqs. 17, 33, 34; finite exit pupil: Hahne et al. 2018), asked of the
main optics (:meth:`lfproc.camera.MainOptics.place_views`): a main lens's views are virtual cameras at
positions F_i with tilts Φ_i and baselines ΔB; an objective's are directions (orthographic), at an
object-space angle each, crossing its pupil at a height, with no baseline."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import Camera, ViewPlacement
from ..errors import LfprocError
from ._slices import _slope_step


def view_offsets(camera: Camera) -> np.ndarray:
    """i = k − c for every view index k = 0 … m̂ − 1."""
    c = camera.center_index
    return np.arange(-c, c + 1)


def place_views(camera: Camera, i=None) -> ViewPlacement:
    """The views at offsets ``i`` (default −c … c) along one axis, as the main optics place them."""
    return camera.main_optics.place_views(camera, view_offsets(camera) if i is None else i)


def _virtual_cameras(camera: Camera, i=None) -> ViewPlacement:
    """:func:`place_views`, refused for orthographic views (directions have no virtual camera, no baseline)."""
    views = place_views(camera, i)
    if views.orthographic:
        raise LfprocError(f"{camera.source or 'camera'}: the views of this camera's optics "
                          f"({camera.main_optics.describe()}) are orthographic, directions without virtual camera "
                          f"positions or baselines; see their object-space angles (lfproc.geometry.view_geometry)")
    return views


def view_slopes(camera: Camera, i=None) -> np.ndarray:
    """Chief-ray slope m_i = −i·p_p/f_s of view offset i under the lens on the optical axis (Eq. 13, Δu = −i)."""
    i = view_offsets(camera) if i is None else np.asarray(i, dtype=np.float64)
    return -i * _slope_step(camera) + 0.0  # + 0.0: the central view is at 0.0, not -0.0


def view_positions_mm(camera: Camera, i=None) -> np.ndarray:
    """Lateral position of each view's virtual optical centre: F_i = m_i·f_U (Eq. 17), per view offset i.

    With a finite exit pupil the centres lie in the entrance pupil plane
    (:func:`~lfproc.geometry.virtual_camera_plane_mm`) at m_i·f_U/(1 − ε/d_A) (Hahne et al. 2018).
    """
    return _virtual_cameras(camera, i).position_mm


def view_tilts_deg(camera: Camera, i=None) -> np.ndarray:
    """Tilt Φ_i = arctan(m_i·(b_U − f_U)/f_U) of each virtual camera's optical axis (Eq. 33), in degrees.

    Zero for every view when b_U = f_U; otherwise the sign of F_i (the contract's convention; the
    paper's Table 4 prints the opposite sign for the same magnitudes). The axis is the view's ray
    through the lens on the optical axis, so a finite exit pupil leaves the tilt unchanged.
    """
    return _virtual_cameras(camera, i).tilt_deg


def baseline_mm(camera: Camera, gap=1) -> np.ndarray | float:
    """Baseline ΔB_g = |F_i − F_(i+g)| = g·p_p·f_U/f_s between views g apart (Eq. 34; ÷ |1 − ε/d_A| with d_A):
    the distance of view offset g's virtual camera from the central one."""
    g = np.asarray(gap, dtype=np.float64)
    b = np.abs(_virtual_cameras(camera, np.abs(g).ravel()).position_mm).reshape(g.shape)
    return float(b) if b.ndim == 0 else b


@dataclass(frozen=True, eq=False)
class ViewGeometry:
    """The views along one axis: offsets i = −c…c and where each looks from, as the optics place them.

    Virtual cameras (a main lens): positions F_i (mm), tilts Φ_i (°) and the adjacent baseline. Orthographic
    views (an objective's): ``baseline_mm`` is ``None``, ``tilt_deg`` is each view's object-space angle (also
    ``angle_deg``), ``position_mm`` where it crosses the objective's pupil; ``inside`` marks the views inside
    the optics' stop (the central row of :func:`views_inside_aperture`).

    Attributes
    ----------
    i : ndarray (m̂,) int
        View offsets from the centre, −c … c.
    position_mm : ndarray (m̂,)
        Where each view looks from: F_i, mm from the optical axis (Eq. 17), or where it crosses the pupil.
    tilt_deg : ndarray (m̂,)
        Its tilt Φ_i (Eq. 33), or an orthographic view's object-space angle, degrees.
    baseline_mm : float or None
        The adjacent baseline (Eq. 34); ``None`` for orthographic views.
    inside : ndarray (m̂,) bool
        Inside the optics' stop.
    lateral_sampling_um : float or None
        The lenses' spacing in the object (a microscope's), µm.
    """

    i: np.ndarray
    position_mm: np.ndarray
    tilt_deg: np.ndarray
    baseline_mm: float | None
    inside: np.ndarray
    lateral_sampling_um: float | None = None

    @property
    def angle_deg(self) -> np.ndarray:
        """The views' object-space angles (orthographic views), or their tilts."""
        return self.tilt_deg

    def records(self) -> list[dict]:
        """One dict per view: ``i``, ``position_mm``, ``tilt_deg`` for virtual cameras; ``i``, ``angle_deg``
        (``None`` where no ray has it) and ``inside_na`` for orthographic views."""
        if self.baseline_mm is None:
            return [dict(i=int(i), angle_deg=(float(t) if np.isfinite(t) else None), inside_na=bool(k))
                    for i, t, k in zip(self.i, self.tilt_deg, self.inside)]
        return [dict(i=int(i), position_mm=float(p), tilt_deg=float(t))
                for i, p, t in zip(self.i, self.position_mm, self.tilt_deg)]


def view_geometry(camera: Camera) -> ViewGeometry:
    """Positions, tilts and the adjacent baseline of all views (Eqs. 17, 33, 34), or an objective's angles.

    Parameters
    ----------
    camera : Camera

    Returns
    -------
    ViewGeometry
        One axis's m̂ views (the lattice is square, so the other axis is the same).
    """
    i = view_offsets(camera)
    views = place_views(camera, i)
    inside = views_inside_aperture(camera)[camera.center_index]
    return ViewGeometry(i, views.position_mm, views.tilt_deg, views.baseline_mm, inside,
                        camera.main_optics.lateral_sampling_um(camera))


def views_inside_aperture(camera: Camera) -> np.ndarray:
    """Boolean mask ``(m̂, m̂)`` of views inside the main optics' stop.

    A main lens: views whose virtual centre (F_iy, F_ix) lies in the entrance pupil, diameter f_U / N (the
    front focal plane for an image-side telecentric lens); views outside it see no light (the dark corners of
    every micro image); without ``f_number`` every view is kept. An objective: views whose image-side ray sine
    is within NA/M (:meth:`lfproc.camera.MainOptics.inside_aperture`).
    """
    return camera.main_optics.inside_aperture(camera)
