"""Focal stacks: refocused slices (Eq. 9) with the tags the commands write (Eqs. 21–31).

:func:`focal_stack` renders the slices and tags them with :func:`lfproc.outputs.slice_metadata`, the function
that writes ``lfproc refocus``'s sidecars, for the views the light field sums (its view mask, the synthetic
aperture): the attributes, ``records()`` and the files of ``save()`` hold the same numbers.
"""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass

import numpy as np

from ..camera import ObjectSpace, SlicesInSpace
from ..errors import LfprocError
from ._defaults import DEFAULT_INTERPOLATION

#: the positions focal_stack takes besides a: the record keys of the built-in object spaces
POSITION_ARGUMENTS = ("distance_mm", "z_um")


@dataclass(frozen=True, eq=False, repr=False)
class FocalStack(SlicesInSpace):
    """Refocused slices of one light field and their geometry.

    One set of tags for any main optics, in the unit and from the origin of ``space`` (the camera's
    :attr:`~lfproc.camera.MainOptics.object_space`), as :class:`lfproc.geometry.SliceGeometry` holds them.

    Attributes
    ----------
    images : ndarray, float32, shape (K, Ny, Nx, C)
        The slices (linear), in the order of ``a``.
    a : ndarray, shape (K,)
        Refocus parameters (Eq. 9).
    depth, near, far, dof : ndarray (K,)
        Where each slice focuses (Eq. 21), its DOF limits nearer to and farther from the optics and its
        depth of field (Eqs. 23, 31), of the views summed, in ``space``'s unit; ``inf`` where infinite.
    space : ObjectSpace
        Unit, origin and record keys of those positions: millimetres from the sensor for a camera,
        micrometres from the native object plane, positive towards the objective, for a microscope.
    distance_mm, near_mm, far_mm, dof_mm : ndarray (K,) or None
        The contract's names of ``depth``, ``near``, ``far``, ``dof`` in mm from the sensor; ``None`` for a
        microscope.
    z_um, z_near_um, z_far_um, dof_um : ndarray (K,) or None
        The same in µm from the native object plane (a microscope's); ``None`` for a photographic camera.
    views_summed : int
        How many views each slice averages (those that carry light, inside ``aperture``).
    aperture_f_number : float or None
        The equivalent f-number of the views summed (``None`` for a microscope: its aperture is an NA).
    interpolation : str
    upsample : int
    camera : Camera
    source : str or None
        The capture (or saved light field) as its absolute path, as the sidecars record it.
    provenance : dict
        The files that shaped the slices (:mod:`lfproc.provenance`).
    """

    images: np.ndarray
    a: np.ndarray
    depth: np.ndarray
    near: np.ndarray
    far: np.ndarray
    dof: np.ndarray
    space: ObjectSpace
    views_summed: int
    aperture_f_number: float | None
    interpolation: str
    upsample: int
    camera: object
    source: str | None
    provenance: dict
    view_mask: np.ndarray | None
    _records: tuple

    def records(self) -> list[dict]:
        """One dict per slice: the keys and values of ``lfproc refocus``'s sidecar (``inf`` for JSON's null)."""
        return copy.deepcopy(list(self._records))

    def save(self, outdir, stem: str | None = None, *, format: str = "tiff", preview: str | None = None,
             stack: str | None = None) -> list[str]:
        """Write what ``lfproc refocus`` writes for these slices: each slice as ``STEM_a….EXT`` with its sidecar
        (``format``: "tiff", "png16", "jpeg" or "exr"), optionally labelled previews (``preview``: "png",
        "jpeg" or "gif") and the slices as one z-stack file (``stack``: "imagej" or "ome").

        ``stem``: the file names' start; default: the capture's name without extension. Returns the image
        paths written (the slices, then the previews and the stack file).
        """
        from ..outputs import lateral_um_per_lens, stack_path, write_focal_stack, write_slice_previews, write_slices

        stem = _stem(stem, self.source)
        outdir = os.fspath(outdir)
        written = write_slices(outdir, stem, self.source, self.camera, list(self.a), self.images, format,
                               view_mask=self.view_mask, upsample=self.upsample, provenance=self.provenance)
        if preview:
            written += list(write_slice_previews(outdir, stem, self.images, self.camera, list(self.a), preview,
                                                 view_mask=self.view_mask) or [])
        if stack:
            written.append(write_focal_stack(stack_path(outdir, stem, stack), self.images, self.records(), self.space,
                                             kind=stack, lens_um=lateral_um_per_lens(self.camera),
                                             upsample=self.upsample))
        return written

    def to_xarray(self):
        """The slices as an ``xarray.DataArray`` (dims slice, y, x, channel; the tags as coordinates along
        ``slice``, provenance in ``attrs``). Needs xarray (not a dependency of lfproc)."""
        try:
            import xarray
        except ImportError:
            raise LfprocError("to_xarray needs the xarray package; install it (pip install xarray)") from None
        coords = {"a": ("slice", self.a)}
        for name, value in zip(self.space.keys, (self.depth, self.near, self.far, self.dof)):
            coords[name] = ("slice", value)
        import json
        attrs = {"views_summed": self.views_summed, "interpolation": self.interpolation, "upsample": self.upsample,
                 "source": self.source or "", "provenance": json.dumps(self.provenance)}
        if self.aperture_f_number is not None:
            attrs["aperture_f_number"] = self.aperture_f_number
        return xarray.DataArray(self.images, dims=("slice", "y", "x", "channel"), coords=coords, attrs=attrs)

    def __len__(self) -> int:
        return int(self.images.shape[0])

    def __repr__(self) -> str:
        k, ny, nx, c = self.images.shape
        where = f"{self.space.name or ''}{_span(self.depth)} {self.space.symbol} {self.space.origin.split(',')[0]}"
        return (f"<FocalStack of {k} slice(s) {ny}x{nx}x{c}, a {_span(self.a)}, {where}, "
                f"{self.views_summed} views summed>")


def focal_stack(lf, a=None, *, distance_mm=None, z_um=None, depth_range_mm=None, z_range_um=None,
                aperture: float | None = None, interpolation: str = DEFAULT_INTERPOLATION,
                upsample: int = 1) -> FocalStack:
    """Refocused slices of a light field (Eq. 9), tagged as ``lfproc refocus`` tags them.

    Parameters
    ----------
    lf : LightField
        With its camera (:func:`lfproc.read_light_field`; an array has no geometry to tag with: wrap it with
        ``LightField.from_views(views, camera, view_mask=...)``).
    a : float or sequence of float, optional
        Refocus parameters. Give exactly one of ``a``, ``distance_mm`` and ``z_um``.
    distance_mm : float or sequence of float, optional
        Distances from the sensor to focus at (a photographic camera; Eq. 21 inverted).
    z_um : float or sequence of float, optional
        Depths from the native object plane in µm, positive towards the objective (a microscope). Positions
        are the optics' own: the one of ``distance_mm`` and ``z_um`` that is their object space's position key.
    depth_range_mm, z_range_um : (float, float), optional
        Instead of listing slices: the fewest slices whose depths of field (those of the views summed) cover this
        range of distances from the sensor (a photographic camera; FAR may be ``inf``) or of depths in µm (a
        microscope), as ``lfproc refocus --depth-range NEAR:FAR`` and ``--z-range Z0:Z1`` plan them. Depths no
        slice can cover are warned about.
    aperture : float, optional
        A synthetic aperture f-number: average only the views inside it (:func:`lfproc.with_aperture`).
    interpolation : {"nearest", "linear", "cubic", "cubic-sharp", "cubic-spline"}
        Default: the commands' (``"cubic-spline"``, :data:`lfproc.api.DEFAULT_INTERPOLATION`).
    upsample : int
        Render on an ``upsample`` times finer grid than the lenses.

    Returns
    -------
    FocalStack

    Raises
    ------
    LfprocError
        No camera, not exactly one of ``a``/``distance_mm``/``z_um``/``depth_range_mm``/``z_range_um``, positions
        in another object space than the optics', slices that image no real object (beyond infinity, nearer than a main lens's front focal
        plane), or slices whose refocused area is under half the image; each states the light field's one
        usable range, in the terms of the argument given.

    Warns
    -----
    LfprocWarning
        Slices where fewer than half the pixels average every view; a microscope's evenly spaced slices far
        closer than their depth of field.
    """
    from ..lightfield import LightField
    from ..outputs import slice_metadata, stack_f_number
    from ..provenance import provenance
    from ..refocusing import refocus
    from ..viewpoints import with_aperture
    from ._checks import check_view_coverage, check_z_step

    if not isinstance(lf, LightField) or lf.camera is None:
        raise LfprocError("focal_stack needs a LightField with its camera (lfproc.read_light_field, or "
                          "LightField.from_views(views, camera, view_mask=...)) to tag the slices")
    camera = lf.camera
    if int(upsample) != upsample or upsample < 1:
        raise LfprocError(f"upsample must be an integer >= 1, got {upsample}")
    lf = with_aperture(lf, aperture)
    ranges = {name: value for name, value in (("depth_range_mm", depth_range_mm), ("z_range_um", z_range_um))
              if value is not None}
    if ranges:
        if len(ranges) > 1 or any(value is not None for value in (a, distance_mm, z_um)):
            raise LfprocError("give exactly one of a=, `distance_mm=`, `z_um=`, `depth_range_mm=` or `z_range_um=`")
        a = _planned(camera, *next(iter(ranges.items())), lf.view_mask)
    a_values, what, asked = _parameters(camera, a, distance_mm, z_um)
    source = None if lf.source is None else os.path.abspath(lf.source)
    check_view_coverage(camera, a_values, lf.lens_shape, lf.source or "light field", lf.view_mask, what, asked)
    check_z_step(camera, a_values)
    images = refocus(lf, a_values, interpolation=interpolation, upsample=int(upsample))
    prov = provenance(lf.inputs)
    records = slice_metadata(source, camera, a_values, lf.view_mask, int(upsample), prov)
    space = camera.main_optics.object_space
    columns = [np.array([r[key] for r in records], dtype=np.float64) for key in ("a",) + tuple(space.keys)]
    summed = records[0].get("views_summed", lf.m_hat ** 2)
    return FocalStack(images, *columns, space, views_summed=int(summed),
                      aperture_f_number=stack_f_number(camera, records[0]), interpolation=interpolation,
                      upsample=int(upsample), camera=camera, source=source, provenance=prov,
                      view_mask=lf.view_mask, _records=tuple(records))


def _parameters(camera, a, distance_mm, z_um):
    """(the slices' a, the argument given, the positions as given or None) from exactly one of ``a``,
    ``distance_mm`` and ``z_um``: positions are the optics' own (the one that is their position key), turned
    into a by the optics (Eq. 21 inverted for a main lens)."""
    from .. import geometry

    given = [name for name, value in zip(("a",) + POSITION_ARGUMENTS, (a, distance_mm, z_um)) if value is not None]
    if len(given) != 1:
        raise LfprocError(f"give exactly one of a=, `distance_mm=` or `z_um=`, got {', '.join(given) or 'none'}")
    name = given[0]
    space = camera.main_optics.object_space
    values = np.atleast_1d(np.asarray({"a": a, "distance_mm": distance_mm, "z_um": z_um}[name], dtype=np.float64))
    if name != "a" and name != space.position_key:   # positions in another object space than the optics'
        own = f"{space.position_key}= or " if space.position_key in POSITION_ARGUMENTS else ""
        raise LfprocError(f"{name}= names positions the optics of this camera ({camera.main_optics.describe()}) do not "
                          f"use: they place slices in {space.symbol} {space.origin}; give {own}a=")
    # positions may be infinite where the optics have a slice at infinity (distances); a never
    finite = np.isfinite(values) if name == "a" else np.array([math.isfinite(v) or space.holds(v) for v in values.ravel()])
    if values.ndim != 1 or values.size == 0 or not np.all(finite):
        raise LfprocError(f"{name}= must be one number or a non-empty sequence of finite numbers")
    asked = None
    if name != "a":
        asked, values = values, np.atleast_1d(geometry.position_parameter(camera, values))
    if len(set(values.tolist())) != len(values):
        raise LfprocError(f"{name}= asks for the same slice twice; give each once")
    return [float(v) for v in values], name, asked


def _planned(camera, name: str, bounds, view_mask) -> list[float]:
    """The a of the fewest slices covering ``bounds`` (``depth_range_mm``: the DOF of the views ``view_mask``
    marks, as ``--depth-range``; ``z_range_um``: as ``--z-range Z0:Z1``), the depths left uncovered warned."""
    from .. import geometry
    from ..errors import warn

    try:
        low, high = (float(v) for v in bounds)
    except (TypeError, ValueError):
        raise LfprocError(f"{name}= must be two numbers (near, far), got {bounds!r}") from None
    space = camera.main_optics.object_space
    position = {"depth_range_mm": "distance_mm", "z_range_um": "z_um"}[name]
    if position != space.position_key:
        raise LfprocError(f"{name}= is a range of positions the optics of this camera "
                          f"({camera.main_optics.describe()}) do not use: they place slices in {space.symbol} "
                          f"{space.origin}")
    near, far = float(space.nearer(low, high)), float(space.farther(low, high))
    if name == "z_range_um":
        return [float(v) for v in geometry.plan_slices(camera, near, far, what="z_range_um= ")]
    geometry.check_usable_distances(camera, near, f"{name}=")
    extent = None if view_mask is None else geometry.summed_view_extent(view_mask)
    plan = geometry.plan_depth_range(camera, near, far, view_extent=extent, what=f"{name}= ")
    if not len(plan.a):
        raise LfprocError(f"{name}= {near:g}, {far:g}: no slice can be planned ({plan.uncovered[0][2]})")
    for lo, hi, why in plan.uncovered:
        warn(f"no slice is in focus at {space.interval(*space.low_high(lo, hi))}: {why}")
    return [float(v) for v in plan.a]


def _stem(stem, source) -> str:
    if stem is not None:
        return str(stem)
    if source is None:
        raise LfprocError("save needs stem= for a light field that was not read from a file")
    from ..outputs import output_stem
    return output_stem(source)


def _span(values) -> str:
    values = np.atleast_1d(values)
    lo, hi = float(np.min(values)), float(np.max(values))
    return f"{lo:.4g}" if lo == hi else f"{lo:.4g} to {hi:.4g}"
