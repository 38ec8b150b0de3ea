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
from dataclasses import dataclass

import numpy as np

from .. import geometry
from ..atomic import write_json_atomic, write_text_atomic
from ..outputs import MIN_LONG_SIDE_PX, ToneMap, metres, slice_names, summed_views_metadata, upscale_factor, \
    view_name
from ..viewpoints import with_aperture
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
               index_href: str | None = None, options: PageOptions = PageOptions(), depth_map=None) -> str:
    """Write a viewer page for ``lf`` into ``outdir``; returns the path of its ``index.html``.

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
        A depth map of ``lf`` already computed; computed here (:func:`lfproc.depth`) otherwise.
    """
    from ..api import DEFAULT_INTERPOLATION
    from ..provenance import provenance
    from ..refocus import refocus

    camera = lf.camera
    focus = estimate_depth(lf, a_values, depth_map)
    extent = None if lf.view_mask is None else geometry.summed_view_extent(lf.view_mask)   # DOF of the views summed
    a_values = scene_slices(camera, focus, view_extent=extent) if a_values is None else \
        np.asarray(a_values, dtype=np.float64)
    stack = refocus(lf, a_values, interpolation=DEFAULT_INTERPOLATION)     # the commands' default
    tone = ToneMap.for_images(stack)
    extension = image_extension(lf.lens_shape)
    jobs = []
    apertures = []
    for f_number in page_apertures(camera):
        summed = with_aperture(lf, f_number)
        aperture_stack = stack if f_number is None else refocus(summed, a_values,
                                                                          interpolation=DEFAULT_INTERPOLATION)
        folder = "slices" if f_number is None else f"slices/f{f_number:g}"
        apertures.append(_aperture_record(camera, summed.view_mask, f_number, a_values, stem, folder, extension))
        for k, record in enumerate(apertures[-1]["slices"]):
            jobs.append((os.path.join(outdir, record["image"]), lambda k=k, s=aperture_stack: tone(s[k])))
    slices = apertures[0]["slices"]
    views = _view_records(camera, stem, extension, getattr(lf, "view_mask", None), getattr(lf, "view_centre", None))
    for item in views["items"]:
        ky, kx = item["view"]
        jobs.append((os.path.join(outdir, item["image"]), lambda ky=ky, kx=kx: tone(lf.views[ky, kx])))
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
        "unit": "um" if camera.is_microscope else "mm",
        "calibration": calibration or {},
        "index_href": index_href,
        "provenance": provenance(lf.inputs),
    }
    write_json_atomic(os.path.join(outdir, "geometry.json"), data)
    maps = {"slice_index": encode_array(slice_index),
            ("z_um" if camera.is_microscope else "distance_mm"): encode_array(focus.distance_mm),
            "confidence": encode_array(np.round(focus.confidence * 255).astype(np.uint8))}
    page = os.path.join(outdir, "index.html")
    write_text_atomic(page, render_page(data, maps))
    return page


def page_apertures(camera) -> list:
    """The synthetic apertures a page offers: ``None`` (every view with light), then 2, 4 and 8 times the
    main lens's f-number (two, four and six stops) while they hold more than the central view (one view
    does not refocus; needs ``f_number``)."""
    if camera.f_number is None:
        return [None]
    widest, narrowest = geometry.aperture_limits(camera)
    return [None] + [widest * k for k in (2.0, 4.0, 8.0)
                     if widest * k <= narrowest and geometry.aperture_views(camera, widest * k).sum() > 1]


def _aperture_record(camera, view_mask, f_number, a_values, stem: str, folder: str, extension: str) -> dict:
    """One aperture of the page: its label, equivalent f-number, views summed and slices with their DOF."""
    extent, extra = summed_views_metadata(camera, view_mask)
    names = slice_names(stem, a_values)
    slices = [dict(record, image=f"{folder}/{names[k]}{extension}")
              for k, record in enumerate(geometry.slice_geometry(camera, a_values, extent).records())]
    n_views = extra.get("views_summed", camera.m_hat ** 2)
    equivalent = extra.get("aperture_f_number", geometry.equivalent_f_number(camera))
    label = ("all views" if f_number is None else f"f/{f_number:g}") + \
        f" ({n_views} view{'' if n_views == 1 else 's'}, {geometry.aperture_text(camera, extent)})"
    summed = np.argwhere(np.ones((camera.m_hat,) * 2, bool) if view_mask is None else view_mask).tolist()
    return {"f_number": f_number, "aperture_f_number": equivalent, "views_summed": n_views, "label": label,
            "summed_views": summed, "slices": slices}


def _view_records(camera, stem: str, extension: str, view_mask=None, view_centre=None) -> dict:
    """The views inside the aperture (and, with ``view_mask``, carrying light) with their virtual cameras
    (Eqs. 17, 33, 34) and image paths.

    ``marker_mm`` (y, x) is where the page's aperture diagram draws each view: its virtual camera,
    ``position_mm``, seen in the orientation of the pictures. The main lens inverts the image, so the
    pictures show the scene turned by 180° and a virtual camera at +x in object space sits at −x in
    them: a view whose near objects shift left (the camera moved right, as the picture shows it) is
    drawn to the right.
    """
    from ..viewpoints import viewpoint_geometry

    keep = geometry.views_inside_aperture(camera)
    if view_mask is not None:
        keep = keep & np.asarray(view_mask, dtype=bool)
    def marker(meta):   # the pictures are turned by 180° (objective + tube lens invert too: angles flip)
        y, x = meta["angle_deg"] if camera.is_microscope else meta["position_mm"]
        return [-y + 0.0, -x + 0.0]

    items = [dict(meta, image=f"views/{view_name(stem, *vg.view)}{extension}", marker_mm=marker(meta))
             for row in viewpoint_geometry(camera, view_centre) for vg in row if keep[vg.view]
             for meta in (vg.metadata(),)]
    if camera.is_microscope:   # orthographic views, placed by their object-space angles
        scope = camera.microscope
        angles = geometry.microscope_views(camera).angle_deg
        c = camera.center_index
        return {"m_hat": camera.m_hat, "center": c, "lateral_sampling_um": geometry.lateral_sampling_um(camera),
                "aperture_radius_deg": math.degrees(math.asin(scope.numerical_aperture / scope.immersion_index)),
                "angle_step_deg": abs(float(angles[c + 1] - angles[c])) if c else 1.0, "items": items}
    return {"m_hat": camera.m_hat, "center": camera.center_index, "baseline_mm": geometry.baseline_mm(camera, 1),
            "aperture_radius_mm": (camera.main_focal_length_mm / (2 * camera.f_number)) if camera.f_number else None,
            "items": items}


def _depth_record(camera, focus, a_far: float, a_near: float) -> dict:
    """The depth map's image, method and colour legend (ticks in metres at their place on the scale)."""
    from ..colours import DEPTH_COLOURS

    ticks = []
    for t in np.linspace(0.0, 1.0, 5):
        a = a_far + t * (a_near - a_far)
        if camera.is_microscope:
            z = float(a * geometry.z_per_a_um(camera))
            ticks.append({"t": float(t), "z_um": z, "label": f"{z:.3g} um"})
            continue
        distance = math.inf if a <= geometry.infinity_parameter(camera) else geometry.slice_distance_mm(camera, a)
        ticks.append({"t": float(t), "distance_mm": distance, "label": metres(distance)})
    searched = f" over {len(focus.sweep_a)} slices (a {focus.sweep_a[0]:.3f} to {focus.sweep_a[-1]:.3f})" \
        if len(focus.sweep_a) else ""
    return {"image": "depth.png", "method": focus.method + searched,
            "min_confidence": focus.min_confidence, "colours": [list(c) for c in DEPTH_COLOURS], "ticks": ticks,
            "colour_scale": "linear in a (disparity), far = first colour, near = last; grey = low confidence"}


def camera_summary(camera) -> list[list[str]]:
    """(label, value) rows describing the camera for people."""
    if camera.is_microscope:
        return _microscope_summary(camera)
    focus_mm = geometry.slice_distance_mm(camera, 0.0)
    rows = [
        ("camera", camera.name or "(unnamed)"),
        ("main lens", f"f = {camera.main_focal_length_mm:g} mm"
                      + (f", f/{camera.f_number:g}" if camera.f_number else "")),
        ("focused at (a = 0)", metres(focus_mm)),
        ("micro lenses", f"{camera.grid}, pitch {camera.mla_pitch_mm * 1000:g} µm, "
                         f"f = {camera.mla_focal_length_mm:g} mm"),
        ("pixels", f"{camera.pixel_pitch_mm * 1000:g} µm ({camera.effective_pixel_pitch_mm * 1000:.3f} µm after "
                   f"resampling to {camera.m_hat} x {camera.m_hat} views)"),
        ("baseline of adjacent views", f"{geometry.baseline_mm(camera, 1):.3f} mm"),
    ]
    exit_pupil = getattr(camera, "exit_pupil_distance_mm", math.inf)
    rows.append(("exit pupil", "telecentric (at infinity)" if not math.isfinite(exit_pupil) else f"{exit_pupil:g} mm"))
    return [list(r) for r in rows]


def _microscope_summary(camera) -> list[list[str]]:
    scope = camera.microscope
    rows = [
        ("camera", camera.name or "(unnamed)"),
        ("objective", f"{scope.objective_magnification:g}x / NA {scope.numerical_aperture:g}, immersion n = "
                      f"{scope.immersion_index:g}, tube lens {scope.tube_lens_focal_length_mm:g} mm"),
        ("focused at (a = 0)", "the native object plane (z = 0 µm)"),
        ("micro lenses", f"{camera.grid}, pitch {camera.mla_pitch_mm * 1000:g} µm, "
                         f"f = {camera.mla_focal_length_mm:g} mm"),
        ("lateral sampling", f"{geometry.lateral_sampling_um(camera):.4g} µm per lens in the sample"),
        ("depth per unit of a", f"{geometry.z_per_a_um(camera):.4g} µm"),
        ("refocusing", "aplanatic (sine condition)" if geometry.uses_aplanatic(camera) else "paraxial"),
    ]
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
    if data.get("unit") == "um":
        depths = [s["z_um"] for s in data["slices"]]
        span = f"{min(depths):.3g} to {max(depths):.3g} um"
    else:
        distances = [math.inf if s["distance_mm"] is None else s["distance_mm"] for s in data["slices"]]
        span = f"{metres(min(distances))} to {metres(max(distances))}"
    return {"stem": data["stem"], "href": f"{relative}/index.html", "thumbnail": f"{relative}/{middle['image']}",
            "source": data["source"], "slices": len(data["slices"]), "range": span}
