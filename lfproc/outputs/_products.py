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


def slice_metadata(source: str, camera, a_values) -> list[dict]:
    """The contract's sidecar fields of each slice: source, a, distance_mm, near_mm, far_mm, dof_mm.

    A microscope's: source, a, z_um, z_near_um, z_far_um, dof_um, and ``refocus_shifts`` ("aplanatic"
    where :func:`lfproc.refocus` follows the sine condition for this camera, else "paraxial").
    """
    records = [dict(source=source, **rec) for rec in geometry.slice_geometry(camera, np.asarray(a_values)).records()]
    if getattr(camera, "microscope", None) is not None:
        shifts = "aplanatic" if geometry.uses_aplanatic(camera) else "paraxial"
        records = [dict(rec, refocus_shifts=shifts) for rec in records]
    return records


def write_slices(outdir: str, stem: str, source: str, camera, a_values, images: np.ndarray,
                 fmt: str = "tiff") -> list[str]:
    """Write each refocused slice with its sidecar; returns the image paths."""
    from ..io import write_image, write_sidecar

    paths = []
    names = slice_names(stem, a_values)
    for name, meta, image in zip(names, slice_metadata(source, camera, a_values), images):
        path = os.path.join(outdir, name + FORMATS[fmt])
        write_image(path, image, meta, fmt)
        write_sidecar(path, meta)
        paths.append(path)
    return paths


def write_views(outdir: str, stem: str, source: str, camera, views: np.ndarray, fmt: str = "tiff",
                keep: np.ndarray | None = None) -> list[str]:
    """Write each view (or those ``keep[ky, kx]`` marks) with the contract's sidecar; returns the paths.

    Two files are written at a time (OpenImageIO releases the GIL while it encodes and writes), which
    keeps the disk busy between one file's open and the next: 225 Illum views reach about half the
    disk's sequential speed instead of a third (docs/benchmarks-commands.md).
    """
    from concurrent.futures import ThreadPoolExecutor

    from ..io import write_image, write_sidecar

    jobs = []
    for row in viewpoint_geometry(camera):
        for vg in row:
            ky, kx = vg.view
            if keep is None or keep[ky, kx]:
                path = os.path.join(outdir, view_name(stem, ky, kx) + FORMATS[fmt])
                jobs.append((path, views[ky, kx], dict(source=source, **vg.metadata())))

    def write(job):
        path, image, meta = job
        write_image(path, image, meta, fmt)
        write_sidecar(path, meta)
        return path

    with ThreadPoolExecutor(max_workers=2) as pool:
        return list(pool.map(write, jobs))


def masked_views(views: np.ndarray, keep: np.ndarray | None) -> np.ndarray:
    """``views`` with every view that ``keep[ky, kx]`` does not mark set to 0 (a copy; ``views`` if no mask)."""
    if keep is None or np.all(keep):
        return views
    return np.where(np.asarray(keep, bool)[:, :, None, None, None], views, np.float32(0))


def write_view_mosaic(outdir: str, stem: str, source: str, camera, views: np.ndarray, fmt: str = "tiff",
                      keep: np.ndarray | None = None) -> str:
    """All views tiled into one image (view (ky, kx) at block (ky, kx)), with a sidecar of every view.

    ``keep`` (m̂ × m̂ booleans, e.g. :func:`lfproc.geometry.views_inside_aperture`): the blocks of views
    it does not mark are black (0), and the sidecar lists which views are shown.
    """
    from ..io import write_image, write_sidecar

    meta = {"source": source, "layout": "block (ky, kx) holds view [ky, kx]", "views_per_side": int(views.shape[0])}
    if camera.is_microscope:
        meta["lateral_sampling_um"] = geometry.lateral_sampling_um(camera)
    else:
        meta["baseline_mm"] = geometry.baseline_mm(camera, 1)
    if keep is not None:
        meta["blacked_out"] = ("views outside the objective's NA are 0" if camera.is_microscope else
                               "views outside the main lens aperture are 0")
    path = os.path.join(outdir, f"{stem}_views_mosaic{FORMATS[fmt]}")
    write_image(path, mosaic(masked_views(views, keep)), meta, fmt)
    listed = [vg.metadata() for row in viewpoint_geometry(camera) for vg in row
              if keep is None or keep[vg.view[0], vg.view[1]]]
    write_sidecar(path, dict(meta, views=listed))
    return path
