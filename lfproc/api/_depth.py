"""Depth maps with their tags: :func:`depth_map` (the estimate of :func:`lfproc.depth`) and ``.save``
(what ``lfproc depth`` writes)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError


@dataclass(frozen=True, eq=False, repr=False)
class DepthResult:
    """A depth map of one light field with its tags.

    Every attribute of :class:`lfproc.depth.DepthMap` is one of this too (``depth``, ``near``, ``far`` and
    their ``space``; the contract's ``distance_mm``, ``near_mm``, ``far_mm`` or ``z_um``, ``z_near_um``,
    ``z_far_um``; ``confidence``, ``a``, ``allfocus`` …), and so is every tag of the sidecars
    ``lfproc depth`` writes (``method``, ``a_searched``, ``a_step``, ``view_step``, ``min_confidence``,
    ``lens_grid``, ``aperture_f_number``; ``unit``: "mm", or "um" for a microscope).

    Attributes
    ----------
    depth_map : lfproc.depth.DepthMap
    source : str or None
    provenance : dict
    depth_range_mm : tuple or None
    """

    depth_map: object
    source: str | None
    provenance: dict
    depth_range_mm: tuple | None
    _lf: object

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        dm = object.__getattribute__(self, "depth_map")
        if hasattr(dm, name):
            return getattr(dm, name)
        tags = self.tags()
        if name in tags:
            return tags[name]
        raise AttributeError(f"'DepthResult' object has no attribute {name!r}")

    @property
    def unit(self) -> str:
        return self.depth_map.space.unit

    def tags(self) -> dict:
        """The fields every sidecar of ``lfproc depth`` shares (source, camera, method, the searched range …,
        provenance)."""
        camera = self._lf.camera
        tags = dict(source=self.source, camera=camera.name if camera is not None else None,
                    **self.depth_map.metadata())
        if self.depth_range_mm is not None:
            tags["depth_range_mm"] = [float(v) for v in self.depth_range_mm]
        tags["provenance"] = self.provenance
        return tags

    def save(self, outdir, stem: str | None = None, *, point_cloud: bool = True) -> dict:
        """Write what ``lfproc depth`` writes: ``STEM_depth.tif``, ``STEM_depth_confidence.tif``,
        ``STEM_allfocus.tif``, ``STEM_depth_preview.png`` and (a photographic camera, ``point_cloud``)
        ``STEM_depth_points.ply``, each with its sidecar. Returns name → path."""
        from ..depth import write_depth_outputs
        from ._focal import _stem

        paths = write_depth_outputs(os.fspath(outdir), _stem(stem, self.source), self._lf, self.depth_map,
                                    source=self.source, camera=self._lf.camera,
                                    depth_range_mm=self.depth_range_mm, point_cloud=point_cloud,
                                    provenance=self.provenance)
        paths.pop("depth_map", None)
        return paths

    def summary(self) -> str:
        """One line: how much is known and the range of the known depths."""
        from ..depth import summary_line
        return summary_line(self.depth_map)

    def __repr__(self) -> str:
        ny, nx = self.depth_map.a.shape
        return f"<DepthResult {ny}x{nx} lenses: {self.summary()}>"


def depth_map(lf, *, depth_range_mm=None, z_range_um=None, z_step_um=None, aperture: float | None = None,
              min_confidence: float | None = None, **options) -> DepthResult:
    """A metric depth map of ``lf`` (:func:`lfproc.depth`), tagged as ``lfproc depth`` tags it.

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
        Further keyword arguments of :func:`lfproc.depth`.

    Returns
    -------
    DepthResult
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
        raise LfprocError(f"min_confidence= must be in [0, 1], got {min_confidence}")
    if z_range_um is not None:
        if depth_range_mm is not None:
            raise LfprocError("give depth_range_mm= (cameras) or z_range_um= (microscopes), not both")
        geometry.require_space(camera, NATIVE_PLANE_UM, "z_range_um= (micrometres)")
        z0, z1 = (float(v) for v in z_range_um)
        if not (math.isfinite(z0) and math.isfinite(z1)) or z0 == z1:
            raise LfprocError(f"z_range_um= must be two different finite depths in um, got {z_range_um!r}")
        a0, a1 = (float(a) for a in geometry.position_parameter(camera, np.array([z0, z1])))
        options["a_range"] = (min(a0, a1), max(a0, a1))
        if z_step_um is not None:   # a step in z as a step in a (z is linear in a through the native object plane)
            options["step"] = float(geometry.position_parameter(camera, float(z_step_um))) - \
                float(geometry.position_parameter(camera, 0.0))
    lf = with_aperture(lf, aperture)
    dm = depth(lf, depth_range_mm=depth_range_mm, camera=camera, min_confidence=min_confidence, **options)
    source = None if lf.source is None else os.path.abspath(lf.source)
    return DepthResult(dm, source, provenance(lf.inputs),
                       None if depth_range_mm is None else tuple(float(v) for v in depth_range_mm), lf)
