"""What ``lfproc views`` writes for one light field: only the views that carry light.

A view that decoding left dark (``LightField.view_mask``) or that lies outside the main lens
aperture (with ``inside_aperture``) holds no picture: it is not written at all, and the mosaic (if
asked for) shows the lit views only, cropped to the rows and columns of views that hold any, with the
dark ones black and a labelled preview PNG beside it. :func:`shown_views` says which views those are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import geometry
from ._previews import write_mosaic_preview, write_view_gif, write_view_previews
from ._products import write_view_mosaic, write_views


@dataclass(frozen=True)
class ViewSet:
    """The views a light field's outputs show and why the others are left out.

    Attributes
    ----------
    keep : ndarray of bool, shape (m̂, m̂)
        The views that are written: lit, and inside the aperture where that was asked for.
    lit : int
        How many views carry light (the decoder's view mask).
    outside_aperture : int
        Lit views left out because they lie outside the main lens aperture (``inside_aperture``).
    """

    keep: np.ndarray
    lit: int
    outside_aperture: int

    @property
    def total(self) -> int:
        return int(self.keep.size)

    def summary(self) -> str:
        """``"45 of 121 views written (76 without light)"``: one phrase for the command's line."""
        dark = self.total - self.lit
        parts = [f"{dark} without light"] if dark else []
        if self.outside_aperture:
            parts.append(f"{self.outside_aperture} outside the aperture")
        return f"{int(self.keep.sum())} of {self.total} views written" + (f" ({', '.join(parts)})" if parts else "")


def shown_views(lf, inside_aperture: bool = False) -> ViewSet:
    """The views of ``lf`` that carry light (and lie inside the aperture with ``inside_aperture``)."""
    m = lf.views.shape[0]
    lit = np.ones((m, m), bool) if lf.view_mask is None else np.asarray(lf.view_mask, bool)
    keep = lit & geometry.views_inside_aperture(lf.camera) if inside_aperture else lit
    return ViewSet(keep, int(lit.sum()), int(lit.sum() - keep.sum()))


def write_view_set(outdir: str, stem: str, source: str, lf, fmt: str = "tiff", *, mosaic: bool = False,
                   gif: bool = False, inside_aperture: bool = False, preview: str | None = None,
                   provenance: dict | None = None) -> list[str]:
    """The lit views (see module docstring), optionally their mosaic with its preview PNG, labelled
    per-view previews (``preview``: ``"png"`` or ``"jpeg"``) and a labelled animation; returns the paths.
    ``provenance`` (:mod:`lfproc.provenance`) goes into the views' and the mosaic's metadata."""
    shown = shown_views(lf, inside_aperture)
    written = write_views(outdir, stem, source, lf.camera, lf.views, fmt, shown.keep, lf.view_centre, provenance)
    if preview:
        written += write_view_previews(outdir, stem, lf.views, shown.keep, lf.camera, preview, centre=lf.view_centre)
    if mosaic:
        written.append(write_view_mosaic(outdir, stem, source, lf.camera, lf.views, fmt, shown.keep,
                                         lf.view_centre, provenance))
        written.append(write_mosaic_preview(outdir, stem, lf.views, shown.keep, camera=lf.camera))
    if gif:
        written.append(write_view_gif(outdir, stem, lf.views, shown.keep, lf.camera, centre=lf.view_centre))
    return written
