"""One viewer page: the refocused stack, the views, the depth map and the geometry of a light field.

Layout of a page folder::

    index.html        the page: HTML, CSS, JavaScript and its data inline (works from file://)
    geometry.json     the same data minus the per-lens maps: slices, views, camera, calibration
    slices/STEM_a+1.017.png …   one 8-bit sRGB image per slice (names as lfproc refocus)
    slices/f8/STEM_a+1.017.png … the same slices through each narrower synthetic aperture (f/8 …)
    views/STEM_view_05_05.png … one per view inside the main lens aperture
    depth.png         the depth map, coloured (legend in metres on the page)

``index.html`` is written last, so a page exists only when all its images do.
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass

import numpy as np

from .. import geometry
from ..atomic import write_json_atomic, write_text_atomic
from ..outputs import MIN_LONG_SIDE_PX, ToneMap, metres, slice_names, summed_views_metadata, upscale_factor, \
    view_name
from ._estimate import estimate_depth
from ._images import depth_colours, image_extension, write_all
from ._page import encode_array, render_page
from ._plan import scene_slices, sharpest_slice, slice_intervals_a


@dataclass(frozen=True)
class PageOptions:
    """How a page shows its images: enlarged to ``min_long_side`` px by ``upscale`` (nearest or smooth)."""

    min_long_side: int = MIN_LONG_SIDE_PX
    upscale: str = "smooth"


def build_page(lf, outdir: str, *, source: str, stem: str, a_values=None, calibration: dict | None = None,
               index_href: str | None = None, options: PageOptions = PageOptions(), depth_map=None,
               focal_stack=None) -> str:
    """Write a viewer page for ``lf`` into ``outdir``; returns the path of its ``index.html``.

    The slices and views are those of the Python API (:func:`lfproc.focal_stack`, :func:`lfproc.view_stack`):
    the commands' interpolation, the light field's view mask, a microscope's per-view shifts, and their tags.

    Parameters
    ----------
    lf : LightField
        Decoded, with its camera.
    source : str
        The capture's path (shown and recorded).
    stem : str
        Prefix of the image names.
    a_values : sequence of float, optional
        The slices to show; default: planned for the scene (:func:`scene_slices`).
    calibration : dict, optional
        Grid summary for the page (:func:`calibration_summary`).
    index_href : str, optional
        Link back to an index of several captures.
    depth_map : lfproc.depth.DepthMap, optional
        A depth map of ``lf`` already computed; computed here (:func:`lfproc.depth_map`) otherwise.
    focal_stack : lfproc.FocalStack, optional
        ``lfproc.focal_stack(lf, a=a_values)`` already computed (every view with light, the page's first
        aperture); refocused here otherwise. Its ``a`` must be ``a_values``.
    """
    from ..provenance import provenance

    camera = lf.camera
    space = camera.main_optics.object_space
    focus = estimate_depth(lf, a_values, depth_map)
    extent = None if lf.view_mask is None else geometry.summed_view_extent(lf.view_mask)   # DOF of the views summed
    a_values = scene_slices(camera, focus, view_extent=extent) if a_values is None else \
        np.asarray(a_values, dtype=np.float64)
    if focal_stack is not None and not np.array_equal(np.asarray(focal_stack.a, dtype=np.float64), a_values):
        raise ValueError("build_page: focal_stack.a must be the page's a_values")
    stacks = [(f_number, focal_stack if f_number is None and focal_stack is not None
               else _focal_stack(lf, a_values, f_number)) for f_number in page_apertures(camera)]
    tone = ToneMap.for_images(stacks[0][1].images)
    extension = image_extension(lf.lens_shape)
    jobs = []
    apertures = []
    for f_number, stack in stacks:
        folder = "slices" if f_number is None else f"slices/f{f_number:g}"
        apertures.append(_aperture_record(camera, stack, f_number, stem, folder, extension))
        for k, record in enumerate(apertures[-1]["slices"]):
            jobs.append((os.path.join(outdir, record["image"]), lambda k=k, s=stack.images: tone(s[k])))
    slices = apertures[0]["slices"]
    view_set = _view_stack(lf)
    views = _view_records(camera, view_set, stem, extension)
    for k, item in enumerate(views["items"]):
        jobs.append((os.path.join(outdir, item["image"]), lambda k=k: tone(view_set.images[k])))
    intervals = slice_intervals_a(camera, a_values, extent)
    a_far, a_near = float(intervals.min()), float(intervals.max())
    jobs.append((os.path.join(outdir, "depth.png"),
                 lambda: depth_colours(focus.a, focus.confidence, a_far, a_near, focus.min_confidence)))
    write_all(jobs)
    slice_index = sharpest_slice(camera, a_values, focus.a, extent)
    data = {
        "format": "lfproc-viewer-1",
        "source": source,
        "stem": stem,
        "lens_shape": list(lf.lens_shape),
        "display": {"scale": upscale_factor(lf.lens_shape, options.min_long_side), "upscale": options.upscale,
                    "tone_map": {"black": tone.black, "white": tone.white, "description": tone.describe()}},
        "slices": slices,
        "apertures": apertures,
        "views": views,
        "depth": _depth_record(camera, focus, a_far, a_near),
        "camera": camera_summary(camera),
        "unit": space.unit,
        "calibration": calibration or {},
        "index_href": index_href,
        "provenance": provenance(lf.inputs),
    }
    write_json_atomic(os.path.join(outdir, "geometry.json"), data)
    maps = {"slice_index": encode_array(slice_index),
            space.position_key: encode_array(focus.distance_mm),
            "confidence": encode_array(np.round(focus.confidence * 255).astype(np.uint8))}
    page = os.path.join(outdir, "index.html")
    write_text_atomic(page, render_page(data, maps))
    return page


def _focal_stack(lf, a_values, f_number):
    """:func:`lfproc.focal_stack` of the page's slices through aperture ``f_number`` (``None``: every view with
    light). Its coverage warning is the command's to give (``lfproc viewer`` checks the slices it is asked for);
    the page itself says nothing."""
    from ..api import focal_stack
    from ..errors import LfprocWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LfprocWarning)
        return focal_stack(lf, a=[float(a) for a in a_values], aperture=f_number)


def _view_stack(lf):
    """:func:`lfproc.view_stack` of the views with light inside the aperture (every lit view where the camera
    file gives no aperture: the main lens's f-number, an objective's NA)."""
    from ..api import view_stack

    return view_stack(lf, inside_aperture=lf.camera.main_optics.image_aperture_sine is not None)


def page_apertures(camera) -> list:
    """The synthetic apertures a page offers: ``None`` (every view with light), then 2, 4 and 8 times the
    main lens's f-number (two, four and six stops) while they hold more than the central view (one view
    does not refocus; needs ``f_number``: an objective's orthographic views have an NA, not f-numbers)."""
    if geometry.place_views(camera, [0]).orthographic or camera.main_optics.view_pupil(camera).widest is None:
        return [None]
    widest, narrowest = geometry.aperture_limits(camera)
    return [None] + [widest * k for k in (2.0, 4.0, 8.0)
                     if widest * k <= narrowest and geometry.aperture_views(camera, widest * k).sum() > 1]


def _aperture_record(camera, stack, f_number, stem: str, folder: str, extension: str) -> dict:
    """One aperture of the page: its label, equivalent f-number, the views ``stack`` (a :class:`lfproc.FocalStack`)
    sums (its ``view_mask``) and its slices with their tags: ``a`` and the object space's position, near, far
    and DOF keys (``distance_mm``… or ``z_um``…)."""
    view_mask = stack.view_mask
    extent, _ = summed_views_metadata(camera, view_mask)
    names = slice_names(stem, stack.a)
    columns = [("a", stack.a)] + list(zip(stack.space.keys, (stack.depth, stack.near, stack.far, stack.dof)))
    slices = [dict({key: float(values[k]) for key, values in columns}, image=f"{folder}/{names[k]}{extension}")
              for k in range(len(stack))]
    n_views = stack.views_summed
    label = ("all views" if f_number is None else f"f/{f_number:g}") + \
        f" ({n_views} view{'' if n_views == 1 else 's'}, {geometry.aperture_text(camera, extent)})"
    summed = np.argwhere(np.ones((camera.m_hat,) * 2, bool) if view_mask is None else view_mask).tolist()
    return {"f_number": f_number, "aperture_f_number": stack.aperture_f_number, "views_summed": n_views,
            "label": label, "summed_views": summed, "slices": slices}


def _view_records(camera, view_set, stem: str, extension: str) -> dict:
    """The views of ``view_set`` (a :class:`lfproc.ViewStack`: those inside the aperture that carry light) with
    their virtual cameras (Eqs. 17, 33, 34, as ``lfproc views`` tags them) and image paths.

    ``marker_mm`` (y, x) is where the page's aperture diagram draws each view: its virtual camera,
    ``position_mm``, seen in the orientation of the pictures. The main lens inverts the image, so the
    pictures show the scene turned by 180° and a virtual camera at +x in object space sits at −x in
    them: a view whose near objects shift left (the camera moved right, as the picture shows it) is
    drawn to the right. Orthographic views (an objective's) have no position: they are drawn at their
    object-space angle, ``tilt_deg``, turned likewise (objective + tube lens invert too).
    """
    optics = camera.main_optics
    c = camera.center_index
    views = geometry.place_views(camera)
    places = view_set.tilt_deg if views.orthographic else view_set.position_mm
    items = [dict({key: value for key, value in record.items() if key not in ("source", "provenance")},
                  image=f"views/{view_name(stem, *view_set.view[k])}{extension}",
                  marker_mm=[-float(places[k][0]) + 0.0, -float(places[k][1]) + 0.0])
             for k, record in enumerate(view_set.records())]
    if views.orthographic:   # an objective's views: placed by their angles inside its aperture
        sine = optics.image_aperture_sine     # the stop's rim: the view whose image-side sine is the aperture's
        rim = sine * camera.mla_focal_length_mm / math.sqrt(1.0 - sine * sine) / camera.sample_pitch_mm
        return {"m_hat": camera.m_hat, "center": c, "lateral_sampling_um": optics.lateral_sampling_um(camera),
                "aperture_radius_deg": abs(float(geometry.place_views(camera, [rim]).tilt_deg[0])),
                "angle_step_deg": abs(float(views.tilt_deg[c + 1] - views.tilt_deg[c])) if c else 1.0,
                "items": items}
    pupil = optics.view_pupil(camera)
    return {"m_hat": camera.m_hat, "center": c, "baseline_mm": views.baseline_mm,
            "aperture_radius_mm": pupil.length / (2 * pupil.widest) if pupil.widest else None,
            "items": items}


def _depth_record(camera, focus, a_far: float, a_near: float) -> dict:
    """The depth map's image, method and colour legend (ticks in metres, or a microscope's µm, at their place
    on the scale)."""
    from ..colours import DEPTH_COLOURS

    space = camera.main_optics.object_space
    ticks = []
    for t in np.linspace(0.0, 1.0, 5):
        position = float(geometry.slice_positions(camera, a_far + t * (a_near - a_far)))
        ticks.append({"t": float(t), space.position_key: position, "label": _position_label(space, position)})
    searched = f" over {len(focus.sweep_a)} slices (a {focus.sweep_a[0]:.3f} to {focus.sweep_a[-1]:.3f})" \
        if len(focus.sweep_a) else ""
    return {"image": "depth.png", "method": focus.method + searched,
            "min_confidence": focus.min_confidence, "colours": [list(c) for c in DEPTH_COLOURS], "ticks": ticks,
            "colour_scale": "linear in a (disparity), far = first colour, near = last; grey = low confidence"}


def _position_label(space, position: float) -> str:
    """A position on the page: distances (which reach infinity) in metres, signed depths in their unit."""
    if space.toward_optics < 0:
        return metres(position / space.per_mm)
    return f"{position:.3g} {space.symbol}"


def camera_summary(camera) -> list[list[str]]:
    """(label, value) rows describing the camera for people: its main optics, where they focus at a = 0, the
    micro lenses and pixels, how the views are spaced (the baseline of virtual cameras, or the lateral sampling
    of orthographic views and how they are refocused) and the exit pupil."""
    optics = camera.main_optics
    space = optics.object_space
    views = geometry.place_views(camera, [0])
    rows = [
        ("camera", camera.name or "(unnamed)"),
        ("main optics", optics.describe()),
        ("focused at (a = 0)", f"{_position_label(space, float(geometry.slice_positions(camera, 0.0)))} "
                               f"{space.origin.split(',')[0]}"),
        ("micro lenses", f"{camera.grid}, pitch {camera.mla_pitch_mm * 1000:g} µm, "
                         f"f = {camera.mla_focal_length_mm:g} mm"),
        ("pixels", f"{camera.pixel_pitch_mm * 1000:g} µm ({camera.effective_pixel_pitch_mm * 1000:.3f} µm after "
                   f"resampling to {camera.m_hat} x {camera.m_hat} views)"),
    ]
    if views.orthographic:
        rows += [("lateral sampling", f"{optics.lateral_sampling_um(camera):.4g} µm per lens in the sample"),
                 ("refocusing", "paraxial" if geometry.refocus_slopes(camera) is None else "aplanatic (sine condition)")]
    else:
        rows.append(("baseline of adjacent views", f"{views.baseline_mm:.3f} mm"))
    exit_pupil = optics.exit_pupil_distance_mm
    rows.append(("exit pupil", "telecentric (at infinity)" if not math.isfinite(exit_pupil) else f"{exit_pupil:g} mm"))
    return [list(r) for r in rows]


def calibration_summary(grid, white: str | None = None) -> dict:
    """The lens grid as the page shows it."""
    if grid is None:
        return {}
    summary = {"lattice": grid.kind, "lenses": f"{grid.rows} x {grid.cols}", "pitch_px": round(grid.pitch_px, 4),
               "rotation_deg": round(grid.rotation_deg, 4), "residual_rms_px": round(grid.residual_rms_px, 4)}
    if white:
        summary["white_image"] = white
    return summary


def write_index(outdir: str, pages: list[dict]) -> str:
    """``OUTDIR/index.html`` linking the pages of several captures; ``pages`` as returned by
    :func:`page_entry`. Returns its path."""
    from ._page import render_index

    path = os.path.join(outdir, "index.html")
    write_text_atomic(path, render_index(pages))
    return path


def page_entry(outdir: str, page_dir: str) -> dict:
    """The index card of a page written by :func:`build_page` into ``page_dir`` (read from its geometry.json)."""
    import json

    with open(os.path.join(page_dir, "geometry.json"), encoding="utf-8") as fh:
        data = json.load(fh)
    relative = os.path.relpath(page_dir, outdir).replace(os.sep, "/")
    middle = data["slices"][len(data["slices"]) // 2]
    key = next(k for k in middle if k != "a")     # the slices' position key: distance_mm, z_um, …
    positions = [math.inf if s[key] is None else s[key] for s in data["slices"]]
    if key == "distance_mm":   # distances from the sensor, to infinity: in metres
        span = f"{metres(min(positions))} to {metres(max(positions))}"
    else:
        span = f"{min(positions):.3g} to {max(positions):.3g} {'µm' if data.get('unit') == 'um' else data.get('unit')}"
    return {"stem": data["stem"], "href": f"{relative}/index.html", "thumbnail": f"{relative}/{middle['image']}",
            "source": data["source"], "slices": len(data["slices"]), "range": span}
