"""View stacks: the viewpoint images (Eq. 32) that carry light, each with its virtual camera (Eqs. 17, 33)."""

from __future__ import annotations

import copy
import functools
import os
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError


@dataclass(frozen=True, eq=False, repr=False)
class ViewStack:
    """The views of a light field that carry light (inside the aperture with ``inside_aperture``), as
    ``lfproc views`` writes them.

    Attributes
    ----------
    images : ndarray, float32, shape (K, Ny, Nx, C)
        The views, row by row ([ky, kx] ascending); gathered from the light field when first asked for
        (``save`` writes them without).
    view : ndarray, int, shape (K, 2)
        Each view's index [ky, kx].
    position_mm : ndarray, shape (K, 2)
        [y, x] of its virtual optical centre in the main lens focal plane (Eq. 17); a microscope's: where
        it crosses the objective's pupil.
    tilt_deg : ndarray, shape (K, 2)
        [y, x] tilt of its optical axis (Eq. 33); a microscope's: its object-space angle.
    source : str or None
    provenance : dict
    """

    view: np.ndarray
    position_mm: np.ndarray
    tilt_deg: np.ndarray
    source: str | None
    provenance: dict
    inside_aperture: bool
    _lf: object
    _records: tuple

    @functools.cached_property
    def images(self) -> np.ndarray:
        if not len(self.view):
            return self._lf.views[:0, 0]
        return self._lf.views[self.view[:, 0], self.view[:, 1]]

    def records(self) -> list[dict]:
        """One dict per view: the keys and values of ``lfproc views``'s sidecars."""
        return copy.deepcopy(list(self._records))

    def save(self, outdir, stem: str | None = None, *, format: str = "tiff", mosaic: bool = False,
             gif: bool = False, preview: str | None = None) -> list[str]:
        """Write what ``lfproc views`` writes: each view ``STEM_view_KY_KX.EXT`` with its sidecar, optionally the
        mosaic (with its preview), an animation and labelled previews (``preview``: "png" or "jpeg")."""
        from ..outputs import write_view_set
        from ._focal import _stem

        return write_view_set(os.fspath(outdir), _stem(stem, self.source), self.source, self._lf, format,
                              mosaic=mosaic, gif=gif, inside_aperture=self.inside_aperture, preview=preview,
                              provenance=self.provenance)

    def __len__(self) -> int:
        return len(self.view)

    def __repr__(self) -> str:
        _, _, ny, nx, c = self._lf.views.shape
        return f"<ViewStack of {len(self)} view(s) {ny}x{nx}x{c}>"


def view_stack(lf, *, inside_aperture: bool = False) -> ViewStack:
    """The views of ``lf`` that carry light (Eq. 32), tagged as ``lfproc views`` tags them.

    Parameters
    ----------
    lf : LightField
        With its camera.
    inside_aperture : bool
        Only the views inside the main lens aperture (a microscope: inside the objective's NA).

    Returns
    -------
    ViewStack
    """
    from ..lightfield import LightField
    from ..outputs import shown_views
    from ..provenance import provenance
    from ..viewpoints import viewpoint_geometry

    if not isinstance(lf, LightField) or lf.camera is None:
        raise LfprocError("view_stack needs a LightField with its camera (lfproc.read_light_field) to tag the "
                          "views")
    if inside_aperture and lf.camera.main_optics.image_aperture_sine is None:   # no f-number (nor NA)
        raise LfprocError(f"{lf.camera.source or 'camera'}: `inside_aperture=True` needs main_lens.f_number in "
                          f"the camera file")
    keep = shown_views(lf, inside_aperture).keep
    source = None if lf.source is None else os.path.abspath(lf.source)
    prov = provenance(lf.inputs)
    table = viewpoint_geometry(lf.camera, lf.view_centre)
    chosen = [(ky, kx) for ky in range(lf.m_hat) for kx in range(lf.m_hat) if keep[ky, kx]]
    records = tuple(dict(source=source, **table[ky][kx].metadata(), provenance=prov) for ky, kx in chosen)
    index = np.array(chosen, dtype=int).reshape(-1, 2)
    return ViewStack(index, np.array([r["position_mm"] for r in records], dtype=np.float64),
                     np.array([r["tilt_deg"] for r in records], dtype=np.float64), source, prov,
                     bool(inside_aperture), lf, records)
