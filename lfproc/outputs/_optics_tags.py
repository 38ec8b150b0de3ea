"""What the camera's main optics say about the tags of the outputs: one place for every output writer.

The outputs never ask which kind of main optics a camera has; they ask the optics for data
(:class:`lfproc.camera.MainOptics`) and tag what they get:

* how slice positions are named, ordered and labelled: the optics' object space (millimetres from the
  sensor, micrometres from the native object plane, …): slices are named by position where positions grow
  with a (so names sort like a), else by a;
* how the views are placed (:meth:`~lfproc.camera.MainOptics.place_views`): virtual cameras at positions
  in the entrance pupil (Eq. 17) with a baseline (Eq. 34) and an equivalent f-number, or orthographic
  directions (an object-side telecentric objective), whose aperture is an NA and whose refocusing may follow
  the sine condition (sidecar ``refocus_shifts``);
* the lateral scale: one size of a lens in the object for every depth where the optics have it
  (:meth:`~lfproc.camera.MainOptics.lateral_sampling_um`), else the views' baseline.
"""

from __future__ import annotations

import numpy as np

from .. import geometry


def named_by_position(camera) -> bool:
    """True where slices are named by their position (positions grow with a, so the names sort like a: a
    microscope's z); False where they are named by a (distances from the sensor shrink as a grows), or no
    camera."""
    return camera is not None and camera.main_optics.object_space.toward_optics > 0


def orthographic_views(camera) -> bool:
    """True where the optics place their views as directions (no baseline: an objective), False where each view
    is a virtual camera at a position (Eq. 17), or no camera."""
    return camera is not None and geometry.place_views(camera, [0]).orthographic


def aperture_tags(camera, view_mask=None) -> tuple[float | None, dict]:
    """(view_extent, tags) of slices averaging the views ``view_mask`` marks (all when ``None``).

    With a mask, the DOF follows the views summed (:func:`lfproc.geometry.summed_view_extent`) and the tags
    carry ``views_summed`` and, for virtual cameras, ``aperture_f_number`` (their equivalent f-number);
    orthographic views have no f-number tag (their aperture is an NA).
    """
    if view_mask is None or np.all(view_mask):
        return None, {}
    extent = geometry.summed_view_extent(view_mask)
    summed = int(np.count_nonzero(view_mask))
    if orthographic_views(camera):
        return extent, {"views_summed": summed}
    return extent, {"aperture_f_number": geometry.equivalent_f_number(camera, extent), "views_summed": summed}


def stack_f_number(camera, tags: dict) -> float | None:
    """The equivalent f-number of a focal stack's summed views: ``aperture_f_number`` of its ``tags``
    (:func:`aperture_tags`), else that of every view for virtual cameras, else ``None`` (orthographic views)."""
    f_number = tags.get("aperture_f_number")
    if f_number is None and not orthographic_views(camera):
        f_number = float(geometry.equivalent_f_number(camera))
    return f_number


def slice_shift_tags(camera) -> dict:
    """Sidecar tags of how each slice was shifted: for orthographic views ``refocus_shifts``, "aplanatic" where
    :func:`lfproc.refocus` follows per-view shifts for this camera (:func:`lfproc.geometry.refocus_slopes`),
    else "paraxial"; none for virtual cameras (Eq. 9's shifts always)."""
    if not orthographic_views(camera):
        return {}
    return {"refocus_shifts": "paraxial" if geometry.refocus_slopes(camera) is None else "aplanatic"}


def lens_spacing_tag(camera) -> tuple[str, float]:
    """The mosaic's scale tag: optics with one lateral scale give the object-space size of one lens
    (``"lateral_sampling_um"``); virtual cameras are ``"baseline_mm"`` apart (Eq. 34, g = 1)."""
    sampling = camera.main_optics.lateral_sampling_um(camera)
    if sampling is not None:
        return "lateral_sampling_um", sampling
    return "baseline_mm", geometry.baseline_mm(camera, 1)


def aperture_words(camera) -> str:
    """How the outputs name what bounds the views: "the objective's NA" for orthographic views, else "the
    aperture"."""
    return "the objective's NA" if orthographic_views(camera) else "the aperture"
