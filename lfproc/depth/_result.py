"""The one depth result, :class:`DepthMap`: the arrays of the estimate, the tags ``lfproc depth`` writes, and
``save`` (what ``lfproc depth`` writes)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..camera import SENSOR_MM, ObjectSpace, PositionsInSpace
from ..errors import LfprocError
from ._confidence import MIN_CONFIDENCE

#: the method name written into the outputs' metadata
METHOD = "plane sweep over the refocus parameter a: variance across the views (correspondence) " \
         "checked by the sharpest slice (defocus); parabolic sub-slice minimum; distance by Eqs. 13-31"


@dataclass(frozen=True, eq=False, repr=False)
class DepthMap(PositionsInSpace):
    """Depth of every lens of a light field, on the refocused slices' lens grid, with its tags.

    One set of fields for any main optics, in the unit and from the origin of ``space`` (the optics'
    :attr:`~lfproc.camera.MainOptics.object_space`): millimetres from the sensor for a main lens (Eq. 21),
    micrometres from the native object plane, positive towards the objective, for a microscope.

    Attributes
    ----------
    depth : ndarray (Ny, Nx) float32
        Position of the surface seen at each lens (the image written to ``STEM_depth.tif``); NaN = unknown,
        ``inf`` = at infinity (distances from the sensor only).
    confidence : ndarray (Ny, Nx) float32
        0 (nothing known) … 1.
    near, far : ndarray (Ny, Nx) float32
        Bounds of the depth nearer to and farther from the optics: the slice's DOF (Eqs. 23–31) widened by
        the cost's basin; NaN = unknown.
    a : ndarray (Ny, Nx) float32
        The refocus parameter of the sharpest slice (sub-slice); NaN = unknown.
    allfocus : ndarray (Ny, Nx, C) float32
        Every lens from the slice in focus at its depth.
    method : str
    a_searched : ndarray (K,)
        The refocus parameters of the sweep.
    view_step, view_reach : int
        Every ``view_step``-th view was used, up to ``view_reach`` views from the centre.
    timings_s : dict
        Seconds spent per step.
    aperture_f_number : float or None
        The equivalent f-number of the views used (a synthetic aperture; ``None`` for a microscope).
    space : ObjectSpace
        Unit, origin and record keys of ``depth``, ``near`` and ``far``.
    lit : ndarray (Ny, Nx) bool or None
        The lenses light reached (:func:`lit_lenses`); elsewhere the depth is unknown for want of light, not of
        texture (the preview draws them black). ``None``: not recorded (all counted as lit).
    source : str or None
        The capture (absolute path) as the sidecars record it (set by :func:`lfproc.depth_map`).
    provenance : dict
        The files that shaped the map (:mod:`lfproc.provenance`).
    depth_range_mm : (near, far) or None
        The range searched, where one was given.
    light_field : LightField or None
        The light field the map was estimated from (:meth:`save` writes its point cloud with its grid).
    distance_mm, near_mm, far_mm : ndarray (Ny, Nx) or None
        The contract's names of ``depth``, ``near``, ``far`` in mm from the sensor; ``None`` for a microscope.
    z_um, z_near_um, z_far_um : ndarray (Ny, Nx) or None
        The same in µm from the native object plane (a microscope's); ``None`` for a photographic camera.
    min_confidence : float
        Lenses less confident than this are unknown (NaN).
    unit, a_step, lens_grid, views_used_up_to_offset, camera_name
        The sidecars' tags of the same names (:meth:`tags`).
    """

    depth: np.ndarray
    confidence: np.ndarray
    near: np.ndarray
    far: np.ndarray
    a: np.ndarray
    allfocus: np.ndarray
    method: str = METHOD
    a_searched: np.ndarray = field(default_factory=lambda: np.zeros(0))
    view_step: int = 1
    view_reach: int = 0
    timings_s: dict = field(default_factory=dict)
    aperture_f_number: float | None = None
    space: ObjectSpace = SENSOR_MM
    lit: np.ndarray | None = None
    source: str | None = None
    provenance: dict = field(default_factory=dict)
    depth_range_mm: tuple | None = None
    light_field: object = None
    min_confidence: float = MIN_CONFIDENCE

    @property
    def unit(self) -> str:
        """The unit of ``depth``, ``near`` and ``far`` in record keys: ``"mm"``, or ``"um"`` for a microscope."""
        return self.space.unit

    @property
    def a_step(self) -> float:
        """The step of the sweep in ``a`` (0 for a single slice)."""
        return float(self.a_searched[1] - self.a_searched[0]) if len(self.a_searched) > 1 else 0.0

    @property
    def lens_grid(self) -> list:
        """``[Ny, Nx]``, the lenses of the map."""
        return [int(self.a.shape[0]), int(self.a.shape[1])]

    @property
    def views_used_up_to_offset(self) -> int:
        """``view_reach``, as the sidecars name it."""
        return int(self.view_reach)

    @property
    def camera_name(self) -> str | None:
        """The name of the light field's camera, as the sidecars record it (``None`` without one)."""
        camera = getattr(self.light_field, "camera", None)
        return None if camera is None else camera.name

    def metadata(self) -> dict:
        """Fields shared by every output of this depth map."""
        return {"method": self.method, "a_searched": [float(self.a_searched[0]), float(self.a_searched[-1])],
                "a_step": self.a_step, "view_step": int(self.view_step),
                "views_used_up_to_offset": self.views_used_up_to_offset, "min_confidence": self.min_confidence,
                "lens_grid": self.lens_grid,
                **({} if self.aperture_f_number is None else {"aperture_f_number": self.aperture_f_number})}

    def tags(self) -> dict:
        """The fields every sidecar of ``lfproc depth`` shares (source, camera, method, the searched range …,
        provenance)."""
        tags = dict(source=self.source, camera=self.camera_name, **self.metadata())
        if self.depth_range_mm is not None:
            tags["depth_range_mm"] = [float(v) for v in self.depth_range_mm]
        tags["provenance"] = self.provenance
        return tags

    def save(self, outdir, stem: str | None = None, *, point_cloud: bool = True) -> dict:
        """Write what ``lfproc depth`` writes.

        Parameters
        ----------
        outdir : str or path-like
            The folder (made if missing).
        stem : str, optional
            The files' common start (default: the capture's name without its extension).
        point_cloud : bool
            Also write ``STEM_depth_points.ply`` (a photographic camera only).

        Returns
        -------
        dict
            Name → path of ``STEM_depth.tif``, ``STEM_depth_confidence.tif``, ``STEM_allfocus.tif``,
            ``STEM_depth_preview.png`` and (``point_cloud``) ``STEM_depth_points.ply``, each with its sidecar.
        """
        from ._outputs import write_depth_outputs

        if self.light_field is None:
            raise LfprocError("save needs the depth map of lfproc.depth_map(lf), which keeps its light field")
        if stem is None and self.source is None:
            raise LfprocError("save needs stem= for a light field that was not read from a file")
        if stem is None:
            from ..lightfield import output_stem
            stem = output_stem(self.source)
        return write_depth_outputs(os.fspath(outdir), str(stem), self, point_cloud=point_cloud)

    def summary(self) -> str:
        """One line: how much is known and the range of the known depths."""
        from ._outputs import summary_line
        return summary_line(self)

    def __repr__(self) -> str:
        ny, nx = self.a.shape
        return f"<DepthMap {ny}x{nx} lenses: {self.summary()}>"
