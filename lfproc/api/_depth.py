"""Depth maps with their tags: :func:`depth_map` → :class:`lfproc.DepthMap` (``.save`` writes what
``lfproc depth`` writes)."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np

from ..errors import LfprocError


def depth_map(lf, *, depth_range_mm=None, z_range_um=None, z_step_um=None, aperture: float | None = None,
              min_confidence: float | None = None, **options):
    """A metric depth map of ``lf``, tagged as ``lfproc depth`` tags it (a plane sweep over the refocus parameter:
    the variance across the views checked by the sharpest slice; distances by Eqs. 13–31).

    Parameters
    ----------
    lf : LightField
        With its camera.
    depth_range_mm : (near, far), optional
        Search only these distances from the sensor (``far`` may be ``inf``; a photographic camera).
    z_range_um : (z0, z1), optional
        A microscope: search only these depths, µm from the native object plane; ``z_step_um`` the step.
    aperture : float, optional
        A synthetic aperture f-number (:func:`lfproc.with_aperture`).
    min_confidence : float, optional
        Estimates less confident than this (0–1) are NaN (default 0.1, the commands' default).
    **options
        The sweep's finer controls: ``a_range=(low, high)`` (search these refocus parameters instead), ``step``
        (in a), ``view_step`` (every n-th view), ``interpolation`` (``"cubic"`` or ``"linear"``),
        ``outer_views`` (also the outer ring of views), ``coarse_pass``, ``half_apertures`` (docs/depth.md).

    Returns
    -------
    DepthMap
        The arrays (``depth``, ``near``, ``far``, ``confidence``, ``a``, ``allfocus``; ``(Ny, Nx)`` per lens), in the
        optics' object space (mm from the sensor, or µm from a microscope's native object plane), with the
        sidecars' tags as attributes (``source``, ``provenance``, ``method``, ``a_searched`` …) and ``.save``.

    Raises
    ------
    LfprocError
        No camera, micro images below 3 px, a bad range, step or confidence.
    """
    from .. import geometry
    from ..camera import NATIVE_PLANE_UM
    from ..depth import MIN_CONFIDENCE, depth
    from ..lightfield import LightField
    from ..provenance import provenance
    from ..viewpoints import with_aperture

    if not isinstance(lf, LightField) or lf.camera is None:
        raise LfprocError("depth_map needs a LightField with its camera (lfproc.read_light_field)")
    camera = lf.camera
    if camera.center_index < 1:
        raise LfprocError(f"{camera.source or 'camera'}: depth needs micro images of 3 px or more "
                          f"(decode.micro_image_px >= 3)")
    min_confidence = MIN_CONFIDENCE if min_confidence is None else float(min_confidence)
    if not 0.0 <= min_confidence <= 1.0:
        raise LfprocError(f"`min_confidence=` must be in [0, 1], got {min_confidence}")
    if z_range_um is not None:
        if depth_range_mm is not None:
            raise LfprocError("give `depth_range_mm=` (cameras) or `z_range_um=` (microscopes), not both")
        geometry.require_space(camera, NATIVE_PLANE_UM, "`z_range_um=` (micrometres)")
        z0, z1 = (float(v) for v in z_range_um)
        if not (math.isfinite(z0) and math.isfinite(z1)) or z0 == z1:
            raise LfprocError(f"`z_range_um=` must be two different finite depths in um, got {z_range_um!r}")
        a0, a1 = (float(a) for a in geometry.position_parameter(camera, np.array([z0, z1])))
        options["a_range"] = (min(a0, a1), max(a0, a1))
        if z_step_um is not None:   # a step in z as a step in a (z is linear in a through the native object plane)
            options["step"] = float(geometry.position_parameter(camera, float(z_step_um))) - \
                float(geometry.position_parameter(camera, 0.0))
    lf = with_aperture(lf, aperture)
    dm = depth(lf, depth_range_mm=depth_range_mm, camera=camera, min_confidence=min_confidence, **options)
    source = None if lf.source is None else os.path.abspath(lf.source)
    return dataclasses.replace(dm, source=source, provenance=provenance(lf.inputs), light_field=lf,
                               depth_range_mm=None if depth_range_mm is None else tuple(float(v) for v in depth_range_mm))
