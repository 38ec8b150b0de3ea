"""What the camera's main optics say about the tags of the outputs: one place for every output writer.

The outputs never ask which kind of main optics a camera has (:class:`lfproc.camera.MainLens` or
:class:`lfproc.camera.Microscope`); they ask the optics for data (:class:`lfproc.camera.MainOptics`):

* how slice positions are named, ordered and labelled: the camera's object space
  (:attr:`lfproc.camera.Camera.object_space`: millimetres from the sensor, or micrometres from the native
  object plane), :func:`signed_depths`;
* how the views are placed: by position in the entrance pupil (Eq. 17, a camera's virtual cameras, with a
  baseline, Eq. 34), or by angle (``views_are_orthographic``: an object-side telecentric objective, whose
  views all see one lateral scale, the lenses' object-space pitch), :func:`views_have_angles`. With angles
  the aperture is the objective's NA and the summed views are an NA, not an f-number; refocusing may follow
  the sine condition (sidecar ``refocus_shifts``).
"""

from __future__ import annotations

import numpy as np

from .. import geometry


def signed_depths(camera) -> bool:
    """True where the camera's object space is signed depths (a microscope's µm from the native object plane,
    no infinity), so slices are named and labelled by z; False for distances from the sensor, or no camera."""
    return camera is not None and not camera.object_space.from_sensor


def views_have_angles(camera) -> bool:
    """True where the camera's views are orthographic (each one direction through every lens: a microscope
    objective), False where each view is a virtual camera at a position (Eq. 17)."""
    optics = None if camera is None else camera.main_optics
    return bool(optics is not None and optics.views_are_orthographic)


def aperture_tags(camera, view_mask=None) -> tuple[float | None, dict]:
    """(view_extent, tags) of slices averaging the views ``view_mask`` marks (all when ``None``).

    With a mask, the DOF follows the views summed (:func:`lfproc.geometry.summed_view_extent`) and the tags
    carry ``views_summed`` and, for views at positions, ``aperture_f_number`` (their equivalent f-number);
    views at angles have no f-number tag (their aperture is an NA).
    """
    if view_mask is None or np.all(view_mask):
        return None, {}
    extent = geometry.summed_view_extent(view_mask)
    summed = int(np.count_nonzero(view_mask))
    if views_have_angles(camera):
        return extent, {"views_summed": summed}
    return extent, {"aperture_f_number": geometry.equivalent_f_number(camera, extent), "views_summed": summed}


def stack_f_number(camera, tags: dict) -> float | None:
    """The equivalent f-number of a focal stack's summed views: ``aperture_f_number`` of its ``tags``
    (:func:`aperture_tags`), else that of every view for views at positions, else ``None`` (views at angles)."""
    f_number = tags.get("aperture_f_number")
    if f_number is None and not views_have_angles(camera):
        f_number = float(geometry.equivalent_f_number(camera))
    return f_number


def slice_shift_tags(camera) -> dict:
    """Sidecar tags of how each slice was shifted: for views at angles ``refocus_shifts``, "aplanatic" where
    :func:`lfproc.refocus` follows the sine condition for this camera, else "paraxial"; none for a camera's
    views (Eq. 9's shifts always)."""
    if not views_have_angles(camera):
        return {}
    return {"refocus_shifts": "aplanatic" if geometry.uses_aplanatic(camera) else "paraxial"}


def lens_spacing_tag(camera) -> tuple[str, float]:
    """The mosaic's scale tag: views at angles share one lateral scale, the object-space size of one lens
    (``"lateral_sampling_um"``, :func:`lfproc.geometry.lateral_sampling_um`); views at positions are
    ``"baseline_mm"`` apart (Eq. 34, g = 1)."""
    if views_have_angles(camera):
        return "lateral_sampling_um", geometry.lateral_sampling_um(camera)
    return "baseline_mm", geometry.baseline_mm(camera, 1)


def aperture_words(camera) -> str:
    """How the outputs name what bounds the views: "the objective's NA" for views at angles, else "the
    aperture"."""
    return "the objective's NA" if views_have_angles(camera) else "the aperture"
