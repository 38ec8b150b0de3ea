"""``lfproc geometry``: slice distances and DOF, the virtual cameras and triangulation of a camera file."""

from __future__ import annotations

import math
import sys

from .common import add_aperture_option, dumps_strict, parse_number_list


def register(sub) -> None:
    p = sub.add_parser("geometry", help="distance and DOF of refocused slices, position and tilt of views",
                       description="Print the paraxial geometry (paper Eqs. 13-34; a finite exit pupil as in "
                                   "Hahne et al. 2018) of a camera: for every refocus parameter a its distance and "
                                   "depth of field from the sensor, for every view its virtual camera position, "
                                   "tilt and the baseline, and with --disparity the distance of points seen with "
                                   "those disparities between views G apart. Negative lists work with or without "
                                   "'=': --a -1:1 or --a=-1:1.")
    p.add_argument("--camera", required=True, metavar="CAM", help="camera TOML file")
    p.add_argument("--calib", metavar="GRID.json",
                   help="the grid from 'lfproc calibrate': m̂ from its measured micro image pitch and the views "
                        "decoding delivers from its white image (read once, then from the decoder cache), so that "
                        "every number is the one refocus writes into its sidecars; without it m̂ is the camera "
                        "file's (nominal, unless [decode] micro_image_px states it) and all views count")
    p.add_argument("--a", default=None, metavar="LIST",
                   help="refocus parameters: numbers and inclusive ranges START:STOP[:STEP] (default 0:5)")
    p.add_argument("--z-range", metavar="Z0:Z1[:STEP]",
                   help="microscope cameras: the fewest slices whose depths of field cover Z0..Z1 micrometres from "
                        "the native object plane (positive towards the objective), or with STEP an evenly spaced "
                        "stack")
    p.add_argument("--disparity", metavar="LIST",
                   help="triangulate points seen with these disparities (view pixels, i.e. lenses, signed as "
                        "PlenoptiSign's dx) between views --gap apart")
    p.add_argument("--gap", type=int, default=1, metavar="G",
                   help="with --disparity: views G apart (signed as PlenoptiSign's G; default 1)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--real-rays", action="store_true",
                   help="also trace the model's rays exactly through the main lens's surfaces (a camera with "
                        "main_lens.prescription or [[main_lens.surfaces]]): real distances, DOF and views beside "
                        "the paraxial ones, with the deviation (paraxial - real)/paraxial in %% (Eq. 37)")
    p.add_argument("--plot", metavar="FILE.png", help="also draw each slice's distance and DOF (needs matplotlib)")
    p.add_argument("--wavelength-nm", type=float, default=550.0, metavar="NM",
                   help="wavelength for the Airy limit (default 550)")
    add_aperture_option(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import geometry
    from ..camera import Camera
    from ..errors import LfprocError

    camera = Camera.from_toml(args.camera)
    if args.a is not None and args.z_range is not None:
        raise LfprocError("give --a or --z-range, not both")
    if args.z_range is None:
        a_values = parse_number_list("0:5" if args.a is None else args.a, "--a")
    if not (args.wavelength_nm > 0 and math.isfinite(args.wavelength_nm)):
        raise LfprocError(f"--wavelength-nm must be a positive number, got {args.wavelength_nm}")
    if args.gap == 0:
        raise LfprocError("--gap must be a non-zero number of views (e.g. 1, or -6 as in PlenoptiSign)")
    disparities = None if args.disparity is None else parse_number_list(args.disparity, "--disparity")
    if args.calib is not None:
        camera, aperture = grid_geometry_inputs(camera, args.calib, args.aperture)
    else:
        aperture = synthetic_aperture(camera, args.aperture)
    if args.z_range is not None:      # planned with the m̂ the slices are refocused with
        a_values = [float(a) for a in z_range_parameters(camera, args.z_range)]
    if not camera.object_space.from_sensor:   # an objective: slices in um from the native plane, views by angle
        if getattr(args, "real_rays", False):
            raise LfprocError(f"{args.camera}: --real-rays traces a main lens prescription; a microscope camera has "
                              f"none")
        return _run_microscope(args, camera, a_values, disparities, aperture)
    if getattr(args, "real_rays", False) and camera.main_lens_prescription is None:
        raise LfprocError(f"{args.camera}: --real-rays needs the main lens's surfaces; add main_lens.prescription "
                          f"(a .zmx file) or [[main_lens.surfaces]] to the camera file")
    slices = geometry.slice_geometry(camera, a_values, aperture["extent"])
    views = geometry.view_geometry(camera)
    check = geometry.diffraction_check(camera, args.wavelength_nm * 1e-6, warn=False)
    gaps = geometry.integer_slice_gaps(camera, [a for a in a_values if float(a).is_integer()], aperture["extent"])
    tri = None if disparities is None else geometry.triangulate(camera, disparities, args.gap)
    if args.plot:
        from ..plots import plot_slices
        plot_slices(camera, slices, args.plot)
    plotted = f"plot of each slice's distance and DOF -> {args.plot}\n" if args.plot else ""
    nominal_m_hat_note(args, camera)
    real = getattr(args, "real_rays", False)
    if args.json:
        report = with_aperture_tags(json_report(camera, slices, views, gaps, check, tri), aperture)
        if real:
            from .real_rays import add_real_rays
            report = add_real_rays(report, camera, aperture["extent"])
        print(dumps_strict(report))
        sys.stderr.write(plotted)   # stdout holds exactly one JSON object
        return 0
    real_table = ""
    if real:
        from .real_rays import format_real_rays
        real_table = format_real_rays(camera, slices, views, aperture["extent"])
    sys.stdout.write(aperture_line(aperture) + format_table(camera, slices, views, gaps, check, args.camera, tri)
                     + real_table + plotted)
    return 0


def synthetic_aperture(camera, f_number) -> dict:
    """``--aperture F``: the views inside it (:func:`lfproc.geometry.aperture_views`, checked there), their DOF
    extent and the tags refocus's sidecars carry for them (``aperture_f_number``, ``views_summed``); without
    one, the full micro image (extent ``None``, no tags)."""
    if f_number is None:
        return {"f_number": None, "extent": None, "tags": {}}
    from .. import geometry
    from ..outputs import summed_views_metadata

    extent, tags = summed_views_metadata(camera, geometry.aperture_views(camera, f_number))
    return {"f_number": float(f_number), "extent": extent, "tags": tags}


def nominal_m_hat_note(args, camera) -> None:
    """One line on stderr, once the table is sure to follow, when m̂ is the nominal one a white image would
    override (neither stated in the camera file nor measured: no ``--calib``)."""
    if args.calib is None and not camera.micro_image_px_given:
        print(f"lfproc geometry: note: m̂ {camera.m_hat} is the camera file's nominal one ({camera.pitch_px:.3f} px a "
              f"lens); decoding with a white image takes it from the measured pitch: --calib GRID.json gives the "
              f"numbers refocus writes", file=sys.stderr)


def grid_geometry_inputs(camera, calib: str, f_number):
    """``--calib GRID``: the camera refocus decodes with (m̂ from the grid's measured pitch) and the views it sums
    (those the decoder delivers from the grid's white image, within ``--aperture``), as ``(camera, aperture)``
    of :func:`synthetic_aperture`'s form. The Python route is the light field's own: ``lf.camera`` and
    ``geometry.summed_view_extent(lf.view_mask)``."""
    import warnings

    from .. import geometry
    from ..errors import LfprocWarning
    from ..outputs import summed_views_metadata
    from ..pipeline import prepare_decoding

    with warnings.catch_warnings():       # what decoding would warn of is decoding's to say, not geometry's
        warnings.simplefilter("ignore", LfprocWarning)
        setup = prepare_decoding(camera, calib, cache=True)
    camera = setup.camera
    mask = setup.decoder_for((), "none").views_delivered if setup.has_white else None
    if mask is None:
        print(f"lfproc geometry: note: {calib}: its white image is gone, so the views decoding delivers are not "
              f"known: all views counted", file=sys.stderr)
    if f_number is not None:
        views = geometry.aperture_views(camera, f_number)
        mask = views if mask is None else views & mask
    extent, tags = summed_views_metadata(camera, mask)
    return camera, {"f_number": None if f_number is None else float(f_number), "extent": extent, "tags": tags}


def with_aperture_tags(report: dict, aperture: dict) -> dict:
    """The report with each slice carrying the tags of the views summed, as refocus's sidecars do, and
    ``"aperture"`` for ``--aperture``."""
    if aperture["tags"]:
        report["slices"] = [dict(record, **aperture["tags"]) for record in report["slices"]]
    if aperture["f_number"] is not None:
        report["aperture"] = dict(f_number=aperture["f_number"], **aperture["tags"])
    return report


def aperture_line(aperture: dict, camera=None) -> str:
    tags = aperture["tags"]
    if aperture["f_number"] is None and not tags:
        return ""
    equivalent = f" (f/{tags['aperture_f_number']:.3g} equivalent)" if "aperture_f_number" in tags else ""
    if camera is not None and camera.f_number is None and camera.main_optics.image_aperture_sine is not None and tags:
        # an aperture known only as a sine (an objective's NA/M): microscopists read NA (issue 32)
        from .. import geometry
        equivalent = f" ({geometry.aperture_text(camera, aperture['extent'])})"
    summed = f"{tags['views_summed']} views summed{equivalent}" if tags else "all views summed"
    head = "the views decoding delivers" if aperture["f_number"] is None else \
        f"synthetic aperture f/{aperture['f_number']:g}"
    return f"{head}: {summed}; the DOF follows them\n"


def _run_microscope(args, camera, a_values, disparities, aperture) -> int:
    """A light-field microscope: slices in µm from the native object plane, views by object-space angle."""
    from .. import geometry
    from ..errors import LfprocError
    if disparities is not None:
        raise LfprocError(f"{args.camera}: --disparity triangulates through a main lens; a microscope's depth per "
                          f"disparity is z_per_a_um per lens of shift (see --json)")
    if args.plot:
        raise LfprocError(f"{args.camera}: --plot draws distances from a main lens; not available for a microscope")
    slices = geometry.slice_geometry(camera, a_values, aperture["extent"])
    views = geometry.microscope_views(camera)
    nominal_m_hat_note(args, camera)
    if args.json:
        print(dumps_strict(with_aperture_tags(microscope_report(camera, slices, views), aperture)))
        return 0
    sys.stdout.write(aperture_line(aperture, camera) + format_microscope_table(camera, slices, views, args.camera))
    return 0


def microscope_summary(camera) -> dict:
    """The derived numbers of a microscope camera (JSON-ready), read off its main optics (objective + tube lens)."""
    from .. import geometry
    scope = camera.main_optics
    return dict(m_hat=camera.m_hat, effective_pixel_pitch_mm=camera.effective_pixel_pitch_mm,
                pitch_px=camera.pitch_px, telecentric=True, objective_magnification=scope.objective_magnification,
                numerical_aperture=scope.numerical_aperture, immersion_index=scope.immersion_index,
                objective_focal_length_mm=scope.objective_focal_length_mm,
                axial_magnification=scope.axial_magnification, z_per_a_um=geometry.z_per_a_um(camera),
                lateral_sampling_um=geometry.lateral_sampling_um(camera), na_views=geometry.na_views(camera),
                paraxial_depth_error=geometry.paraxial_depth_error(camera),
                aplanatic=geometry.uses_aplanatic(camera), wavelength_nm=scope.wavelength_mm * 1e6)


def microscope_report(camera, slices, views) -> dict:
    """``slices`` (a, z_um, z_near_um, z_far_um, dof_um), ``views`` (i, angle_deg, inside_na) and the camera."""
    return {"slices": slices.records(), "views": views.records(),
            "lateral_sampling_um": views.lateral_sampling_um, "camera": microscope_summary(camera),
            "provenance": dict(camera.provenance)}


def format_microscope_table(camera, slices, views, path) -> str:
    s = microscope_summary(camera)
    out = [f"microscope {camera.name or path}: {s['objective_magnification']:g}x/{s['numerical_aperture']:g} "
           f"(n = {s['immersion_index']:g}), m = {camera.m_hat} samples per lens "
           f"({camera.pitch_px:.3f} sensor px), {s['lateral_sampling_um']:.4g} µm per lens in the object, "
           f"{s['z_per_a_um']:.4g} µm per unit of a",
           f"refocusing: {'aplanatic (sine condition)' if s['aplanatic'] else 'paraxial'} per-view shifts (a "
           f"paraxial z would be off by up to {100 * s['paraxial_depth_error']:.1f} % at this NA); the DOF adds the "
           f"wave term at {s['wavelength_nm']:.0f} nm",
           "depths from the native object plane [µm], positive towards the objective",
           f"{'a':>8} {'z_far':>11} {'z':>11} {'z_near':>11} {'DOF':>11}"]
    for r in slices.records():
        out.append(f"{r['a']:>+8.4f} {r['z_far_um']:>11.3f} {r['z_um']:>11.3f} {r['z_near_um']:>11.3f} "
                   f"{r['dof_um']:>11.3f}")
    out += ["", f"views: orthographic, object-space angle (sine condition); {s['na_views']} views either side of "
                f"the centre lie inside the NA", f"{'i':>5} {'angle [deg]':>12} {'inside NA':>10}"]
    for r in views.records():
        angle = "-" if r["angle_deg"] is None else f"{r['angle_deg']:.3f}"
        out.append(f"{r['i']:>5d} {angle:>12} {'yes' if r['inside_na'] else 'no':>10}")
    return "\n".join(out) + "\n"


def z_range_parameters(camera, text: str, advise: bool = True):
    """The ``a`` of ``--z-range Z0:Z1[:STEP]`` (µm): the fewest covering slices, or an evenly spaced stack;
    ``advise``: warn of a step far finer than the DOF here (commands that render leave it to focal_stack, which
    says it with the m̂ the light field is decoded with)."""
    from .. import geometry
    from ..errors import LfprocError
    if camera.object_space.from_sensor:   # distances in mm from the sensor: no native object plane
        raise LfprocError(f"{camera.source or 'camera'}: --z-range (micrometres) needs a microscope camera "
                          f"([microscope]); use --depth-range NEAR_MM:FAR_MM for a camera")
    parts = text.split(":")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) not in (2, 3):
        raise LfprocError(f"--z-range: {text!r} must be Z0:Z1 or Z0:Z1:STEP in micrometres, e.g. -50:50 or -50:50:2")
    planned = geometry.plan_z_range(camera, values[0], values[1], values[2] if len(values) == 3 else None)
    if advise:
        from ..api import check_z_step

        check_z_step(camera, planned)       # as focal_stack says it
    return planned


def camera_summary(camera) -> dict:
    """The derived numbers the geometry rests on (JSON-ready; ``inf`` becomes null)."""
    from .. import geometry
    return dict(m_hat=camera.m_hat, effective_pixel_pitch_mm=camera.effective_pixel_pitch_mm,
                sample_pitch_mm=camera.sample_pitch_mm,
                image_distance_mm=camera.image_distance_mm, exit_pupil_distance_mm=camera.exit_pupil_distance_mm,
                telecentric=camera.telecentric, micro_image_scale=geometry.micro_image_scale(camera),
                virtual_camera_plane_mm=geometry.virtual_camera_plane_mm(camera),
                infinity_a=geometry.infinity_parameter(camera))


def json_report(camera, slices, views, gaps, check, tri) -> dict:
    """The contract's keys (``slices``, ``views``, ``baseline_mm``, ``triangulation``) plus additive ones."""
    out = {"slices": slices.records(), "views": views.records(), "baseline_mm": views.baseline_mm,
           "integer_gaps": [dict(a=a, next_a=a + 1.0, near_mm=lo, far_mm=hi) for a, lo, hi in gaps],
           "diffraction": check.record(), "camera": camera_summary(camera),
           "provenance": dict(camera.provenance)}
    if tri is not None:
        out["triangulation"] = tri.records()
    return out


def _mm(value: float, width: int = 11) -> str:
    return f"{'inf':>{width}}" if math.isinf(value) else f"{value:>{width}.3f}"


def format_table(camera, slices, views, gaps, check, path, tri=None) -> str:
    """A readable table in the layout of the paper's Tables 2 and 4."""
    from .. import geometry
    pupil = ("exit pupil at infinity (telecentric)" if camera.telecentric else
             f"exit pupil {camera.exit_pupil_distance_mm:.3f} mm from the MLA (micro images scaled by "
             f"{geometry.micro_image_scale(camera):.6f}, samples {camera.sample_pitch_mm * 1e3:.3f} µm apart)")
    out = [f"camera {camera.name or path}: m = {camera.m_hat} px per micro image, effective pixel pitch "
           f"{camera.effective_pixel_pitch_mm * 1e3:.3f} µm, b_U - f_U = "
           f"{camera.image_distance_mm - camera.main_focal_length_mm:.4f} mm, {pupil}"]
    if camera.provenance:
        out.append("where the camera's numbers came from:")
        out += [f"  {key}: {text}" for key, text in camera.provenance]
    out += ["distances from the sensor [mm]",
            f"{'a':>8} {'near d_a-':>11} {'d_a':>11} {'far d_a+':>11} {'DOF D_a':>11}"]
    for r in slices.records():
        out.append(f"{r['a']:>8g} {_mm(r['near_mm'])} {_mm(r['distance_mm'])} {_mm(r['far_mm'])} {_mm(r['dof_mm'])}")
    for a, lo, hi in gaps:
        out.append(f"  gap between a = {a:g} and {a + 1:g}: {lo:.3f} .. {hi:.3f} mm is in no integer slice's DOF")
    out.append("")
    out.append(f"views (Eqs. 17, 33): baseline of adjacent views {views.baseline_mm:.4f} mm")
    out.append(f"{'i':>5} {'position F_i [mm]':>18} {'tilt [deg]':>11}")
    for r in views.records():
        out.append(f"{r['i']:>5d} {r['position_mm']:>18.4f} {r['tilt_deg']:>11.4f}")
    if tri is not None:
        out.append("")
        out.append("triangulation (PlenoptiSign's G and dx; distance from the sensor)")
        out.append(f"{'G':>5} {'dx [px]':>9} {'B_G [mm]':>10} {'tilt [deg]':>11} {'distance':>11}")
        for r in tri.records():
            out.append(f"{r['gap']:>5} {r['disparity_px']:>9g} {r['baseline_mm']:>10.4f} {r['tilt_deg']:>11.4f} "
                       f"{_mm(r['distance_mm'])}")
    out.append("")
    out.append(check.message())
    return "\n".join(out) + "\n"
