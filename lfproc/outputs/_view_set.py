"""What ``lfproc views`` writes for one light field."""

from __future__ import annotations

from .. import geometry
from ._previews import write_view_gif
from ._products import write_view_mosaic, write_views


def write_view_set(outdir: str, stem: str, source: str, lf, fmt: str = "tiff", *, mosaic: bool = False,
                   gif: bool = False, inside_aperture: bool = False) -> list[str]:
    """The views (all, or those inside the main lens aperture), optionally their mosaic (views outside
    the aperture black there with ``inside_aperture``) and a labelled animation; returns the paths."""
    keep = geometry.views_inside_aperture(lf.camera)
    written = write_views(outdir, stem, source, lf.camera, lf.views, fmt, keep if inside_aperture else None)
    if mosaic:
        written.append(write_view_mosaic(outdir, stem, source, lf.camera, lf.views, fmt,
                                         keep if inside_aperture else None))
    if gif:
        written.append(write_view_gif(outdir, stem, lf.views, keep, lf.camera))
    return written
