"""A main lens's own geometry: what only a photographic main lens has (its f-number's Airy disc, the plane of
its virtual cameras, triangulation between them, real rays through its surfaces).

The functions of :mod:`lfproc.geometry` work for any main optics through their interface
(:class:`lfproc.camera.MainOptics`); the ones built on a main lens's own numbers (f_U, b_U, N, its surfaces:
``_diffraction``, ``_triangulation``, ``_real_rays`` and :func:`virtual_camera_plane_mm` below) take the lens
from :func:`main_lens_of`, which refuses other optics in one line.
"""

from __future__ import annotations

import numpy as np

from ..camera import MainLens
from ..errors import LfprocError


def main_lens_of(camera, what: str) -> MainLens:
    """The camera's main lens, or `LfprocError` (one line) when ``what`` needs one and the optics are another."""
    optics = camera.main_optics
    if not isinstance(optics, MainLens):
        raise LfprocError(f"{getattr(camera, 'source', '') or 'camera'}: {what} needs a main lens ([main_lens]); "
                          f"this camera's optics are a {optics.describe()}")
    return optics


def virtual_camera_plane_mm(camera) -> float:
    """Distance from the sensor of the plane holding every view's virtual optical centre (Eq. 17 generalised,
    :meth:`lfproc.camera.MainLens.virtual_camera_plane_mm`): the main lens front focal plane when telecentric,
    the entrance pupil otherwise; ``inf`` (object-side telecentric views) when d_A = ε."""
    return main_lens_of(camera, "the plane of the virtual cameras").virtual_camera_plane_mm(camera.mla_path_mm)


def chief_ray_heights(camera, lens_heights_mm, distance_mm):
    """Where the central view's chief ray through each lens (height s from the axis, mm) is at ``distance_mm``
    from the sensor: the depth map's point cloud (``lfproc.depth_map``); ``None`` for optics other than a main lens.

    The ray leaves the micro lens with slope m = −s/d_A (0 telecentric), reaches H1U at U = s + m·b_U (Eq. 16),
    passes the front focal plane at F = m·f_U (Eq. 17), so at z from H1U it is at U + (F − U)/f_U·z (Eqs. 18, 19).
    """
    lens = camera.main_optics
    if not isinstance(lens, MainLens):
        return None
    s = np.asarray(lens_heights_mm, dtype=np.float64)
    z = np.asarray(distance_mm, dtype=np.float64) - lens.sensor_path_mm(camera.mla_path_mm)
    d_a, f_u = lens.exit_pupil_distance_mm, lens.focal_length_mm
    m = 0.0 if not np.isfinite(d_a) else -s / d_a
    u = s + m * lens.image_distance_mm
    return u + (m * f_u - u) / f_u * z
