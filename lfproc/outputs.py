"""Output files of refocusing and viewpoint extraction: names, metadata, sidecars (contract).

For an image ``OUTDIR/NAME.EXT`` the sidecar is ``OUTDIR/NAME.json``; the same fields are embedded in
the image's own metadata by :func:`lfproc.io.write_image`. Every file is written atomically.
"""

from __future__ import annotations

import os

import numpy as np

from . import geometry
from .viewpoints import circular_walk, mosaic, viewpoint_geometry

#: output format -> file extension
FORMATS = {"tiff": ".tif", "png16": ".png", "jpeg": ".jpg", "exr": ".exr"}


def slice_name(stem: str, a: float, decimals: int = 3) -> str:
    """``STEM_a+1.500``: sign and (at least) three decimals; -0 is written as +0."""
    return f"{stem}_a{a + 0.0:+.{decimals}f}"


def slice_names(stem: str, a_values) -> list[str]:
    """Names for every slice, with as many decimals (3 to 12) as it takes to keep them apart.

    Raises
    ------
    LfprocError
        When two values of ``a`` are equal to 12 decimals: they would overwrite each other's file.
    """
    from .errors import LfprocError

    values = [float(a) for a in a_values]
    for decimals in range(3, 13):
        names = [slice_name(stem, a, decimals) for a in values]
        if len(set(names)) == len(names):
            return names
    raise LfprocError("two refocus parameters are equal (to 12 decimals): each slice needs its own a; "
                      "remove the duplicate from the list")


def view_name(stem: str, ky: int, kx: int) -> str:
    return f"{stem}_view_{ky:02d}_{kx:02d}"


def slice_metadata(source: str, camera, a_values) -> list[dict]:
    """The contract's sidecar fields of each slice: source, a, distance_mm, near_mm, far_mm, dof_mm."""
    return [dict(source=source, **rec) for rec in geometry.slice_geometry(camera, np.asarray(a_values)).records()]


def write_slices(outdir: str, stem: str, source: str, camera, a_values, images: np.ndarray,
                 fmt: str = "tiff") -> list[str]:
    """Write each refocused slice with its sidecar; returns the image paths."""
    from .io import write_image, write_sidecar

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
    """Write each view (or those ``keep[ky, kx]`` marks) with the contract's sidecar; returns the paths."""
    from .io import write_image, write_sidecar

    paths = []
    for row in viewpoint_geometry(camera):
        for vg in row:
            ky, kx = vg.view
            if keep is not None and not keep[ky, kx]:
                continue
            meta = dict(source=source, **vg.metadata())
            path = os.path.join(outdir, view_name(stem, ky, kx) + FORMATS[fmt])
            write_image(path, views[ky, kx], meta, fmt)
            write_sidecar(path, meta)
            paths.append(path)
    return paths


def write_view_mosaic(outdir: str, stem: str, source: str, camera, views: np.ndarray, fmt: str = "tiff") -> str:
    """All views tiled into one image (view (ky, kx) at block (ky, kx)), with a sidecar of every view."""
    from .io import write_image, write_sidecar

    meta = {"source": source, "layout": "block (ky, kx) holds view [ky, kx]", "views_per_side": int(views.shape[0]),
            "baseline_mm": geometry.baseline_mm(camera, 1)}
    path = os.path.join(outdir, f"{stem}_views_mosaic{FORMATS[fmt]}")
    write_image(path, mosaic(views), meta, fmt)
    write_sidecar(path, dict(meta, views=[vg.metadata() for row in viewpoint_geometry(camera) for vg in row]))
    return path


def display_scale(images: np.ndarray) -> float:
    """One exposure for a whole animation: maps the 99.5th percentile to white."""
    top = float(np.percentile(images, 99.5)) if images.size else 0.0
    return 1.0 / top if top > 0 else 1.0


def write_view_gif(outdir: str, stem: str, views: np.ndarray, mask: np.ndarray | None = None) -> str:
    """An animation walking the views along a circle inside the aperture."""
    from .io import write_gif

    path_views = circular_walk(views.shape[0], mask=mask)
    frames = np.stack([views[k] for k in path_views])
    path = os.path.join(outdir, f"{stem}_views.gif")
    write_gif(path, frames * display_scale(frames), duration_ms=80)
    return path


def write_slice_gif(outdir: str, stem: str, images: np.ndarray) -> str:
    """An animation running through a focal stack in the given order and back."""
    from .io import write_gif

    frames = np.concatenate([images, images[-2:0:-1]]) if len(images) > 2 else images
    path = os.path.join(outdir, f"{stem}_refocus.gif")
    write_gif(path, frames * display_scale(images), duration_ms=150)
    return path


def write_view_set(outdir: str, stem: str, source: str, lf, fmt: str = "tiff", *, mosaic: bool = False,
                   gif: bool = False, inside_aperture: bool = False) -> list[str]:
    """What ``lfproc views`` writes for one light field: the views (all, or those inside the main lens
    aperture), optionally their mosaic (views outside the aperture black there) and an animation."""
    keep = geometry.views_inside_aperture(lf.camera)
    written = write_views(outdir, stem, source, lf.camera, lf.views, fmt, keep if inside_aperture else None)
    if mosaic:
        shown = np.where(keep[:, :, None, None, None], lf.views, np.float32(0)) if inside_aperture else lf.views
        written.append(write_view_mosaic(outdir, stem, source, lf.camera, shown, fmt))
    if gif:
        written.append(write_view_gif(outdir, stem, lf.views, keep))
    return written
