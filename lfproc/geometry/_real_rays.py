"""Real rays: the paraxial model's own rays traced exactly through the main lens's surfaces (Snell's law).

The paper validated its model (Table 2, Table 4) by tracing, in a commercial optics program, the rays
its equations intersect. This module does the same for a camera with a main lens prescription
(:class:`~lfproc.camera.LensPrescription`), vectorised over every ray of a sweep.

Rays (ARCHITECTURE.md, "Real lenses"). A ray leaves the micro lens array (MLA) at height y with the
image-side slope μ of the paraxial model: from the pixel at offset U samples from its micro image
centre through the centre of its micro lens at height s (the micro lens stays paraxial, Eq. 13 with
the finite exit pupil of Hahne et al. 2018):

    μ = U·δ + s/d_A,       δ = p_p/f_s,

so the micro image centre of the lens at s is where U = 0 lands. For slice a, the outermost summed
views i = ±r (r = c, or the ``view_extent``) under lenses 2ar apart are placed symmetrically about the
axis, so each pair meets on the axis; by symmetry one ray of each pair is traced and its axis
crossing in object space is the pair's meeting point:

* d_a: pixel centres, U = r, lens centre s = y = −a·r·p_m (Eqs. 13–14, 20);
* d_a− / d_a+: pixel borders and micro lens borders, U = (2r + t)/2 and y = −(2ar + s)/2·p_m with the
  bounding pairs (s, t) of :mod:`._slices` (Eqs. 24–25, 30), the lens centre at −a·r·p_m; where the
  aberrations swap them, the nearer crossing is d_a− (as ``slice_geometry`` orders its limits);
* ``spread_mm``: the range of the axis crossings of the central pairs of every summed view pair
  i = ±v, v = 1 … ⌊r⌋ and r (spherical aberration of the summed bundle; 0 for a perfect lens).

Traced paraxially (the matrices of :mod:`._transfer`), these rays meet exactly where
:func:`~._slices.slice_geometry` says (the tests check it); traced exactly, they meet where the real
lens puts the slice. A view's real virtual camera is the least-squares convergence point of its chief
rays (pixel offset i under each of the lenses j = −J … J, J = c by default, Eq. 17's bundle) and its
tilt their mean angle to the axis (the paper's Table 4 "Simulation").

The exact trace is meridional: spheres (planes where R = ∞) intersected in closed form, refraction
by the vector form of Snell's law, n·(d × N) = n'·(d' × N). A ray that misses a surface or is totally
reflected, or a pair that does not meet in front of the first surface, gives NaN (``null`` in JSON);
so does a slice whose paraxial distance lies inside or behind the lens. Semi-diameters are not
applied: the rays are the model's, vignetted or not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera, MainLens
from ..errors import LfprocError
from ._exit_pupil import pupil_curvature
from ._main_lens import main_lens_of
from ._slices import _slope_step, _view_extent, slice_geometry


def traces_real_rays(camera) -> bool:
    """Whether the camera's optics can be traced exactly: a main lens given by its surfaces."""
    optics = camera.main_optics
    return isinstance(optics, MainLens) and optics.prescription is not None


def real_ray_lens(camera) -> dict:
    """The lens behind the real rays: where its surfaces came from and its paraxial cardinal points."""
    lens = _require_prescription(camera)
    return dict(source=lens.source, wavelength_nm=lens.wavelength_nm, surfaces=len(lens.surfaces),
                focal_length_mm=lens.focal_length_mm, principal_plane_gap_mm=lens.principal_plane_gap_mm,
                exit_pupil_distance_mm=camera.main_optics.exit_pupil_distance_mm)


def _require_prescription(camera: Camera):
    lens = main_lens_of(camera, "real rays through the main lens's surfaces").prescription
    if lens is None:
        raise LfprocError(f"{camera.source or 'camera'}: real rays need the main lens's surfaces; give "
                          f"main_lens.prescription (a .zmx file) or [[main_lens.surfaces]] in the camera file")
    return lens


@dataclass(frozen=True)
class _Frame:
    """The camera in lens coordinates (mm from the first vertex, towards the image)."""

    vertex: np.ndarray
    curvature: np.ndarray
    n_before: np.ndarray
    n_after: np.ndarray
    z_mla: float
    z_sensor: float


def _frame(camera: Camera) -> _Frame:
    lens = _require_prescription(camera)
    vertex = np.array([lens.vertex_mm(k) for k in range(len(lens.surfaces))])
    z_mla = lens.rear_principal_plane_mm + main_lens_of(camera, "real rays").image_distance_mm
    return _Frame(vertex, np.array([s.curvature for s in lens.surfaces]), np.array(lens.indices_before()),
                  np.array([s.index for s in lens.surfaces]), z_mla,
                  z_mla + camera.mla_focal_length_mm + camera.mla_principal_plane_gap_mm)


def trace_to_object_space(frame: _Frame, y0, slope):
    """Trace rays leaving the MLA at heights ``y0`` with image-side slopes ``slope`` back through the lens.

    Returns
    -------
    (z, y, dz, dy) : ndarrays
        The point where each ray leaves the first surface and its unit direction (dz < 0, towards the
        object); NaN for a ray that misses a surface or is totally reflected.
    """
    y = np.asarray(y0, dtype=np.float64).copy()
    mu = np.asarray(slope, dtype=np.float64)
    norm = np.sqrt(1.0 + mu * mu)
    dz, dy = -1.0 / norm, -mu / norm
    z = np.full_like(y, frame.z_mla)
    with np.errstate(invalid="ignore", divide="ignore"):
        for k in range(len(frame.vertex) - 1, -1, -1):
            c = frame.curvature[k]
            pz = z - frame.vertex[k]
            b = c * (pz * dz + y * dy) - dz
            q = c * (pz * pz + y * y) - 2.0 * pz
            root = np.sqrt(b * b - c * q)                      # NaN: the ray misses the sphere
            t = -q / (b + np.where(b >= 0.0, root, -root))     # the intersection next to the vertex
            z, y = z + t * dz, y + t * dy
            nz, ny = c * (z - frame.vertex[k]) - 1.0, c * y   # unit normal of the sphere (plane: (−1, 0))
            cos_i = -(nz * dz + ny * dy)
            flip = np.where(cos_i < 0.0, -1.0, 1.0)            # orient the normal against the ray
            nz, ny, cos_i = nz * flip, ny * flip, cos_i * flip
            eta = frame.n_after[k] / frame.n_before[k]         # from the medium behind surface k to the one in front
            k2 = 1.0 - eta * eta * (1.0 - cos_i * cos_i)       # < 0: total internal reflection → NaN
            gain = eta * cos_i - np.sqrt(k2)
            dz, dy = eta * dz + gain * nz, eta * dy + gain * ny
    return z, y, dz, dy


def _axis_distance(frame: _Frame, y0, slope) -> np.ndarray:
    """Distance from the sensor where each traced ray crosses the axis in front of the lens; NaN if it does not."""
    z, y, dz, dy = trace_to_object_space(frame, y0, slope)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = -y / dy
        z_cross = z + t * dz
        ok = (t > 0.0) & np.isfinite(z_cross) & (z_cross < frame.vertex[0])
    return np.where(ok, frame.z_sensor - z_cross, np.nan)


def slice_rays(camera: Camera, a, view_extent=None):
    """The rays of each slice: (y0, slope), shape ``(3 + n, …)``: d_a, d_a−, d_a+ and the n spread pairs.

    One ray of each symmetric pair (module docstring); the other is its mirror image.
    """
    a = np.asarray(a, dtype=np.float64)
    r = _view_extent(camera, view_extent)
    pitch, delta, kappa = camera.mla_pitch_mm, _slope_step(camera), pupil_curvature(camera)
    centre = -a * r * pitch
    heights, offsets, centres = [centre], [np.full_like(a, r)], [centre]
    for s in (1.0, -1.0):                                  # near, far (the bounding pairs of _slices)
        t = np.where(2.0 * a * r + s >= 0.0, -s, s)
        heights.append(-(2.0 * a * r + s) / 2.0 * pitch)
        offsets.append((2.0 * r + t) / 2.0)
        centres.append(centre)
    for v in _spread_views(r):
        heights.append(-a * v * pitch)
        offsets.append(np.full_like(a, v))
        centres.append(-a * v * pitch)
    y0 = np.array(np.broadcast_arrays(*heights))
    slope = np.array(np.broadcast_arrays(*offsets)) * delta + np.array(np.broadcast_arrays(*centres)) * kappa
    return y0, slope


def _spread_views(r: float) -> list[float]:
    views = [float(v) for v in range(1, int(math.floor(r)) + 1)]
    if r >= 1.0 and r not in views:
        views.append(r)
    return views


@dataclass(frozen=True, eq=False)
class RealRaySlices:
    """Real-ray distances of slices (mm from the sensor; NaN = the rays do not meet in front of the lens).

    Attributes
    ----------
    a : ndarray (K,)
        Refocus parameters.
    distance_mm, near_mm, far_mm : ndarray (K,)
        Where the traced rays of each slice meet, and its DOF limits, mm from the sensor.
    spread_mm : ndarray (K,)
        How far apart the rays' meeting points lie (aberration), mm.
    """

    a: np.ndarray
    distance_mm: np.ndarray
    near_mm: np.ndarray
    far_mm: np.ndarray
    spread_mm: np.ndarray

    def records(self) -> list[dict]:
        """One ``{"distance_mm", "near_mm", "far_mm", "spread_mm"}`` per slice, ``None`` for null."""
        cols = [np.atleast_1d(x) for x in (self.distance_mm, self.near_mm, self.far_mm, self.spread_mm)]
        return [{k: (None if math.isnan(v) else float(v)) for k, v in
                 zip(("distance_mm", "near_mm", "far_mm", "spread_mm"), row)} for row in zip(*cols)]


def real_ray_slices(camera: Camera, a, view_extent=None) -> RealRaySlices:
    """Real-ray d_a, d_a−, d_a+ and the summed bundle's spread of slices ``a`` (the paper's Table 2 "Simulation").

    Parameters
    ----------
    camera : Camera
        With a main lens prescription.
    a : float or array_like
    view_extent : float, optional
        r, the half-extent of the summed views (default c), as in :func:`~._slices.slice_geometry`.

    Returns
    -------
    RealRaySlices
        Arrays of the shape of ``a`` (at least 1-D). NaN where the rays do not cross in front of the
        lens, where a ray fails, or where the paraxial value lies inside or behind the lens.
    """
    frame = _frame(camera)
    a_arr = np.atleast_1d(np.asarray(a, dtype=np.float64))
    if camera.center_index == 0:
        nan = np.full_like(a_arr, np.nan)
        return RealRaySlices(a_arr, nan, nan, nan, nan)
    y0, slope = slice_rays(camera, a_arr, view_extent)
    d = _axis_distance(frame, y0, slope)
    paraxial = slice_geometry(camera, a_arr, view_extent)
    front = frame.z_sensor - frame.vertex[0]              # the first vertex, from the sensor
    both = np.isfinite(d[1]) & np.isfinite(d[2]) & np.isfinite(d[0])   # order the limits as slice_geometry does
    lo, hi = np.fmin(np.fmin(d[1], d[2]), d[0]), np.fmax(np.fmax(d[1], d[2]), d[0])
    near = np.where(paraxial.near_mm > front, np.where(both, lo, d[1]), np.nan)
    far = np.where(paraxial.far_mm > front, np.where(both, hi, d[2]), np.nan)
    dist = np.where(paraxial.distance_mm > front, d[0], np.nan)
    if len(d) > 3:
        spread = d[3:].max(axis=0) - d[3:].min(axis=0)    # NaN if any pair fails
        spread = np.where(paraxial.distance_mm > front, spread, np.nan)
    else:
        spread = np.full_like(a_arr, np.nan)
    return RealRaySlices(a_arr, dist, near, far, spread)


@dataclass(frozen=True, eq=False)
class RealRayViews:
    """Real virtual cameras: convergence point (lateral position, distance from the sensor) and tilt.

    Attributes
    ----------
    i : ndarray (m̂,) int
        View offsets from the centre.
    position_mm : ndarray (m̂,)
        Lateral position of each virtual camera, mm from the optical axis.
    distance_mm : ndarray (m̂,)
        Its distance from the sensor, mm.
    tilt_deg : ndarray (m̂,)
        Its tilt, degrees.
    """

    i: np.ndarray
    position_mm: np.ndarray
    distance_mm: np.ndarray
    tilt_deg: np.ndarray

    def records(self) -> list[dict]:
        """One ``{"position_mm", "tilt_deg", "distance_mm"}`` per view, ``None`` for null."""
        return [{k: (None if math.isnan(v) else float(v)) for k, v in
                 zip(("position_mm", "tilt_deg", "distance_mm"), row)}
                for row in zip(self.position_mm, self.tilt_deg, self.distance_mm)]


def view_rays(camera: Camera, i, lenses=None):
    """(y0, slope) of the chief rays of views ``i`` (rows) under the lenses j = −J … J (columns)."""
    i = np.atleast_1d(np.asarray(i, dtype=np.float64))
    half = camera.center_index if lenses is None else int(lenses)
    heights = np.arange(-half, half + 1) * camera.mla_pitch_mm
    y0 = np.broadcast_to(heights, (len(i), len(heights)))
    slope = i[:, None] * _slope_step(camera) + heights[None, :] * pupil_curvature(camera)
    return np.array(y0), slope


def real_ray_views(camera: Camera, i=None, lenses=None) -> RealRayViews:
    """Real positions and tilts of the virtual cameras of views ``i`` (the paper's Table 4 "Simulation").

    Parameters
    ----------
    camera : Camera
        With a main lens prescription.
    i : array_like, optional
        View offsets (default −c … c).
    lenses : int, optional
        J: the chief rays under the 2J + 1 lenses nearest the axis (default c).

    Returns
    -------
    RealRayViews
        ``position_mm``: lateral position of the least-squares convergence point of each view's
        chief rays (the paraxial F_i); ``distance_mm``: its distance from the sensor; ``tilt_deg``:
        the rays' mean angle to the axis (the sign convention of ``view_tilts_deg``). NaN where the
        rays are parallel or a ray fails.
    """
    frame = _frame(camera)
    i = np.arange(-camera.center_index, camera.center_index + 1) if i is None else np.atleast_1d(i)
    y0, slope = view_rays(camera, i, lenses)
    z, y, dz, dy = trace_to_object_space(frame, y0, slope)
    # least squares: sum over rays of (I − d dᵀ)(x − p) = 0, a 2×2 system per view
    pzz, pzy, pyy = 1.0 - dz * dz, -dz * dy, 1.0 - dy * dy
    a11, a12, a22 = pzz.sum(1), pzy.sum(1), pyy.sum(1)
    b1 = (pzz * z + pzy * y).sum(1)
    b2 = (pzy * z + pyy * y).sum(1)
    det = a11 * a22 - a12 * a12
    with np.errstate(invalid="ignore", divide="ignore"):
        ok = np.abs(det) > 1e-18 * np.maximum(a11 * a22, 1e-300)
        zc = np.where(ok, (a22 * b1 - a12 * b2) / det, np.nan)
        yc = np.where(ok, (a11 * b2 - a12 * b1) / det, np.nan)
    tilt = np.degrees(np.arctan2(-dy, -dz)).mean(axis=1)    # the light's direction, as Eq. 33
    return RealRayViews(np.asarray(i), yc + 0.0, frame.z_sensor - zc, tilt + 0.0)
