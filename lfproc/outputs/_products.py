"""The data products: refocused slices, views and the view mosaic, linear, each with its metadata.

For an image ``OUTDIR/NAME.EXT`` the sidecar is ``OUTDIR/NAME.json`` (contract); the same fields are
embedded in the image's own metadata by :func:`lfproc.io.write_image`. Every file is written atomically.
"""

from __future__ import annotations

import os

import numpy as np

from .. import geometry
from ..viewpoints import mosaic, viewpoint_geometry
from ._names import FORMATS, slice_names, view_name
from ._optics_tags import aperture_tags, aperture_words, lens_spacing_tag, slice_shift_tags


def summed_views_metadata(camera, view_mask=None) -> tuple[float | None, dict]:
    """(view_extent, extra tags) of slices averaging the views ``view_mask`` marks (all when ``None``).

    With a mask, the DOF follows the views summed (:func:`lfproc.geometry.summed_view_extent`) and the
    tags carry ``views_summed`` and, for a camera's views, ``aperture_f_number`` (their equivalent
    f-number; :func:`~._optics_tags.aperture_tags`).
    """
    return aperture_tags(camera, view_mask)


def slice_metadata(source: str, camera, a_values, view_mask=None, upsample: int = 1,
                   provenance: dict | None = None) -> list[dict]:
    """The contract's sidecar fields of each slice: source, a and the four keys of the camera's object space
    (:attr:`lfproc.camera.ObjectSpace.keys`: distance_mm, near_mm, far_mm, dof_mm; a microscope's z_um,
    z_near_um, z_far_um, dof_um), and for orthographic views ``refocus_shifts`` ("aplanatic" where
    :func:`lfproc.refocus` follows the sine condition for this camera, else "paraxial";
    :func:`~._optics_tags.slice_shift_tags`).

    The DOF is that of the views ``view_mask`` marks (the light field's, e.g. after
    :func:`lfproc.with_aperture`), which also adds ``aperture_f_number`` and ``views_summed``. Slices refocused
    on a finer grid (``upsample`` s > 1: (N − 1)·s + 1 pixels per axis, pixel p at lens p/s) carry ``upsample``.
    ``provenance`` (:func:`lfproc.provenance.provenance`), when given, is the last key of every record.
    """
    extent, extra = summed_views_metadata(camera, view_mask)
    if int(upsample) != 1:
        extra["upsample"] = int(upsample)
    extra.update(slice_shift_tags(camera))
    records = geometry.slice_geometry(camera, np.asarray(a_values), extent).records()
    if geometry.traces_real_rays(camera):   # a real lens: its rays beside the model's
        real = geometry.real_ray_slices(camera, np.asarray(a_values, dtype=np.float64).ravel(), extent).records()
        records = [dict(rec, real_rays=r) for rec, r in zip(records, real)]
    tail = {} if provenance is None else {"provenance": provenance}
    return [dict(source=source, **rec, **extra, **tail) for rec in records]


def display_exposure(images, fmt: str):
    """For ``fmt == "jpeg"`` (8-bit, for viewing only): the set's :class:`ToneMap` and its metadata, else
    ``(None, {})``. A JPEG of linear values straight through the sRGB curve looks pale and flat; with one
    exposure for the whole set (black and white points from its percentiles) slices and views compare
    and use the display's range. TIFF/PNG16/EXR stay linear data."""
    if fmt != "jpeg":
        return None, {}
    from ._tone import ToneMap

    tone = ToneMap.for_images(images)
    return tone, {"tone_map": tone.describe(), "tone_black": tone.black, "tone_white": tone.white}


def _exposed(image: np.ndarray, tone) -> np.ndarray:
    """``image`` scaled so that ``tone``'s black is 0 and its white 1 (the writer then encodes sRGB)."""
    if tone is None:
        return image
    return (np.asarray(image, np.float32) - np.float32(tone.black)) / np.float32(tone.white - tone.black)


def write_slices(outdir: str, stem: str, source: str, camera, a_values, images: np.ndarray,
                 fmt: str = "tiff", view_mask=None, upsample: int = 1, provenance: dict | None = None) -> list[str]:
    """Write each refocused slice with its sidecar (DOF of the views ``view_mask`` marks; ``upsample``: the
    grid the slices were refocused on, :func:`slice_metadata`); returns the paths (JPEGs: :func:`display_exposure`)."""
    from ..io import write_image, write_sidecar

    paths = []
    names = slice_names(stem, a_values, camera)
    tone, tone_meta = display_exposure(images, fmt)
    for name, meta, image in zip(names, slice_metadata(source, camera, a_values, view_mask, upsample, provenance),
                                 images):
        path = os.path.join(outdir, name + FORMATS[fmt])
        meta.update(tone_meta)
        write_image(path, _exposed(image, tone), meta, fmt)
        write_sidecar(path, meta)
        paths.append(path)
    return paths


def write_views(outdir: str, stem: str, source: str, camera, views: np.ndarray, fmt: str = "tiff",
                keep: np.ndarray | None = None, centre=None, provenance: dict | None = None) -> list[str]:
    """Write each view (or those ``keep[ky, kx]`` marks) with the contract's sidecar; returns the paths.

    ``centre``: where the decoder read the central view (``LightField.view_centre``): the tags follow it.
    ``provenance`` (:mod:`lfproc.provenance`), when given, is added to every view's metadata.

    Two files are written at a time (OpenImageIO releases the GIL while it encodes and writes), which
    keeps the disk busy between one file's open and the next: 225 Illum views reach about half the
    disk's sequential speed instead of a third (docs/benchmarks-commands.md).
    """
    from concurrent.futures import ThreadPoolExecutor

    from ..io import write_image, write_sidecar

    jobs = []
    shown = views if keep is None or fmt != "jpeg" else views[np.asarray(keep, bool)]   # a copy for JPEGs only
    tone, tone_meta = display_exposure(shown, fmt)
    real = _real_view_tags(camera, centre)
    tail = {} if provenance is None else {"provenance": provenance}
    for row in viewpoint_geometry(camera, centre):
        for vg in row:
            ky, kx = vg.view
            if keep is None or keep[ky, kx]:
                path = os.path.join(outdir, view_name(stem, ky, kx) + FORMATS[fmt])
                jobs.append((path, _exposed(views[ky, kx], tone),
                             dict(source=source, **vg.metadata(), **real(ky, kx), **tone_meta, **tail)))

    def write(job):
        path, image, meta = job
        write_image(path, image, meta, fmt)
        write_sidecar(path, meta)
        return path

    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(write, jobs))


def _real_view_tags(camera, centre):
    """``(ky, kx) -> {"real_rays": {"position_mm": [y, x], "tilt_deg": [y, x]}}`` for a camera with a lens
    prescription (each axis traced in its meridional plane, :func:`lfproc.geometry.real_ray_views`); else ``{}``."""
    if not geometry.traces_real_rays(camera):
        return lambda ky, kx: {}
    offsets = geometry.view_offsets(camera)
    cy, cx = (0.0, 0.0) if centre is None else (float(centre[0]), float(centre[1]))
    ry, rx = (geometry.real_ray_views(camera, offsets + c).records() for c in (cy, cx))
    return lambda ky, kx: {"real_rays": {key: [ry[ky][key], rx[kx][key]] for key in ("position_mm", "tilt_deg")}}


def masked_views(views: np.ndarray, keep: np.ndarray | None) -> np.ndarray:
    """``views`` with every view that ``keep[ky, kx]`` does not mark set to 0 (a copy; ``views`` if no mask)."""
    if keep is None or np.all(keep):
        return views
    return np.where(np.asarray(keep, bool)[:, :, None, None, None], views, np.float32(0))


def shown_block(keep: np.ndarray | None, m_hat: int) -> tuple[slice, slice]:
    """The rows and columns of views a mosaic shows: those holding at least one view ``keep`` marks."""
    if keep is None or not np.any(keep):
        return slice(0, m_hat), slice(0, m_hat)
    rows, cols = np.flatnonzero(np.any(keep, axis=1)), np.flatnonzero(np.any(keep, axis=0))
    return slice(int(rows[0]), int(rows[-1]) + 1), slice(int(cols[0]), int(cols[-1]) + 1)


def mosaic_of_shown(views: np.ndarray, keep: np.ndarray | None, gap: int = 0) -> tuple[np.ndarray, tuple]:
    """The mosaic of the views ``keep`` marks, cropped to their rows and columns (others black), and the
    index ``(ky0, kx0)`` of the view in its top-left block."""
    rows, cols = shown_block(keep, views.shape[0])
    shown = masked_views(views, keep)[rows, cols]
    return mosaic(shown, gap=gap), (rows.start, cols.start)


def write_view_mosaic(outdir: str, stem: str, source: str, camera, views: np.ndarray, fmt: str = "tiff",
                      keep: np.ndarray | None = None, centre=None, provenance: dict | None = None) -> str:
    """The views ``keep`` marks (all without it) tiled into one image, with a sidecar of every view shown.

    ``keep`` (m̂ × m̂ booleans: the views that carry light, e.g. ``LightField.view_mask``, possibly
    combined with :func:`lfproc.geometry.views_inside_aperture`): the mosaic is cropped to the rows and
    columns of views it marks, so block (by, bx) holds view [ky0 + by, kx0 + bx] with ``first_view`` =
    [ky0, kx0] in the metadata; blocks of unmarked views inside that range are black (0), and the
    sidecar lists exactly the views shown.
    """
    from ..io import write_image, write_sidecar

    tiled, (ky0, kx0) = mosaic_of_shown(views, keep)
    tone, tone_meta = display_exposure(views if keep is None else views[np.asarray(keep, bool)], fmt)
    listed = [vg.metadata() for row in viewpoint_geometry(camera, centre) for vg in row
              if keep is None or keep[vg.view[0], vg.view[1]]]
    meta = {"source": source, "layout": "block (by, bx) holds view [ky0 + by, kx0 + bx]",
            "first_view": [ky0, kx0], "views_per_side": int(views.shape[0]), "views_shown": len(listed), **tone_meta}
    key, spacing = lens_spacing_tag(camera)
    meta[key] = spacing
    if keep is not None and not np.all(keep):
        meta["blacked_out"] = f"views without light (or outside {aperture_words(camera)}) are 0 and not listed"
    if provenance is not None:
        meta["provenance"] = provenance
    path = os.path.join(outdir, f"{stem}_views_mosaic{FORMATS[fmt]}")
    write_image(path, _exposed(tiled, tone), meta, fmt)
    write_sidecar(path, dict(meta, views=listed))
    return path
