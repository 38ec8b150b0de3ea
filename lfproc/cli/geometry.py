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
    p.add_argument("--calib", dest="grid", metavar="GRID.json",
                   help="the grid from 'lfproc calibrate': m̂ from its measured micro image pitch and the views "
                        "decoding delivers from its white image (read once, then from the decoder cache), so that "
                        "every number is the one refocus writes into its sidecars; without it m̂ is the camera "
                        "file's (nominal, unless [decode] micro_image_px states it) and all views count")
    p.add_argument("--a", default=None, metavar="LIST",
                   help="refocus parameters: numbers and inclusive ranges START:STOP[:STEP] (default 0:5)")
    p.add_argument("--z-range", dest="z_range_um", metavar="Z0:Z1[:STEP]",
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
    from ..camera import SENSOR_MM, Camera
    from ..errors import LfprocError

    camera = Camera.from_toml(args.camera)
    if args.a is not None and args.z_range_um is not None:
        raise LfprocError("give --a or --z-range, not both")
    if args.z_range_um is None:
        a_values = parse_number_list("0:5" if args.a is None else args.a, "--a")
    if not (args.wavelength_nm > 0 and math.isfinite(args.wavelength_nm)):
        raise LfprocError(f"--wavelength-nm must be a positive number, got {args.wavelength_nm}")
    if args.gap == 0:
        raise LfprocError("--gap must be a non-zero number of views (e.g. 1, or -6 as in PlenoptiSign)")
    disparities = None if args.disparity is None else parse_number_list(args.disparity, "--disparity")
    if args.grid is not None:
        camera, aperture = grid_geometry_inputs(camera, args.grid, args.aperture)
    else:
        aperture = synthetic_aperture(camera, args.aperture)
    if args.z_range_um is not None:      # planned with the m̂ the slices are refocused with
        a_values = [float(a) for a in z_range_parameters(camera, args.z_range_um)]
    real = getattr(args, "real_rays", False)
    if real and not geometry.traces_real_rays(camera):
        raise LfprocError(f"{args.camera}: --real-rays needs the main lens's surfaces; add main_lens.prescription "
                          f"(a .zmx file) or [[main_lens.surfaces]] to the camera file")
    if args.plot:
        geometry.require_space(camera, SENSOR_MM, "--plot (each slice's distance and DOF)")
    slices = geometry.slice_geometry(camera, a_values, aperture["extent"])
    views = geometry.view_geometry(camera)
    if disparities is not None and views.baseline_mm is None:
        raise LfprocError(f"{args.camera}: --disparity triangulates between virtual cameras; this camera's views are "
                          f"orthographic (directions, no baselines): a depth is a shift of lenses per unit of a")
    tri = None if disparities is None else geometry.triangulate(camera, disparities, args.gap)
    perspective = views.baseline_mm is not None     # virtual cameras: integer gaps and the Airy check (Eq. 22)
    check = geometry.diffraction_check(camera, args.wavelength_nm * 1e-6, warn=False) if perspective else None
    gaps = geometry.integer_slice_gaps(camera, [a for a in a_values if float(a).is_integer()], aperture["extent"]) \
        if perspective else []
    if args.plot:
        from ..plots import plot_slices
        plot_slices(camera, slices, args.plot)
    plotted = f"plot of each slice's distance and DOF -> {args.plot}\n" if args.plot else ""
    nominal_m_hat_note(args, camera)
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
    sys.stdout.write(aperture_line(aperture, camera) + format_table(camera, slices, views, gaps, check, args.camera,
                                                                    tri) + real_table + plotted)
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
    if args.grid is None and not camera.micro_image_px_given:
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
    from ..api import prepare_decoding

    with warnings.catch_warnings():       # what decoding would warn of is decoding's to say, not geometry's
        warnings.simplefilter("ignore", LfprocWarning)
        setup = prepare_decoding(camera, grid=calib, cache=True)
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
    if camera is not None and "aperture_f_number" not in tags and tags:
        # an aperture known only as a sine (an objective's NA/M): microscopists read NA (issue 32)
        from .. import geometry
        equivalent = f" ({geometry.aperture_text(camera, aperture['extent'])})"
    summed = f"{tags['views_summed']} views summed{equivalent}" if tags else "all views summed"
    head = "the views decoding delivers" if aperture["f_number"] is None else \
        f"synthetic aperture f/{aperture['f_number']:g}"
    return f"{head}: {summed}; the DOF follows them\n"


def z_range_parameters(camera, text: str, advise: bool = True):
    """The ``a`` of ``--z-range Z0:Z1[:STEP]`` (µm): the fewest covering slices, or an evenly spaced stack;
    ``advise``: warn of a step far finer than the DOF here (commands that render leave it to focal_stack, which
    says it with the m̂ the light field is decoded with)."""
    from .. import geometry
    from ..camera import NATIVE_PLANE_UM
    from ..errors import LfprocError
    geometry.require_space(camera, NATIVE_PLANE_UM, "--z-range (use --depth-range NEAR_MM:FAR_MM for a camera)")
    parts = text.split(":")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) not in (2, 3):
        raise LfprocError(f"--z-range: {text!r} must be Z0:Z1 or Z0:Z1:STEP in micrometres, e.g. -50:50 or -50:50:2")
    space = camera.main_optics.object_space
    near, far = (float(v) for v in (space.nearer(values[0], values[1]), space.farther(values[0], values[1])))
    step = values[2] if len(values) == 3 else None
    planned = geometry.plan_slices(camera, near, far, step=step, what="--z-range ")
    if advise:
        from ..api import check_z_step

        check_z_step(camera, planned)       # as focal_stack says it
    return planned


def camera_summary(camera, views) -> dict:
    """The derived numbers the geometry rests on (JSON-ready; ``inf`` becomes null): the optics' own
    (:meth:`lfproc.camera.MainOptics.summary`) and, for orthographic views, how they are refocused."""
    from .. import geometry
    summary = camera.main_optics.summary(camera)
    if views.baseline_mm is None:
        summary.update(geometry.refocus_summary(camera))
    return summary


def json_report(camera, slices, views, gaps, check, tri) -> dict:
    """The contract's keys (``slices``, ``views``, ``baseline_mm``, ``triangulation``) plus additive ones; for
    orthographic views (a microscope's) ``lateral_sampling_um`` in place of the baseline."""
    out = {"slices": slices.records(), "views": views.records()}
    if views.baseline_mm is not None:
        near, far = slices.space.keys[1:3]
        out.update(baseline_mm=views.baseline_mm,
                   integer_gaps=[{"a": a, "next_a": a + 1.0, near: lo, far: hi} for a, lo, hi in gaps],
                   diffraction=check.record())
    else:
        out["lateral_sampling_um"] = views.lateral_sampling_um
    out.update(camera=camera_summary(camera, views), provenance=dict(camera.provenance))
    if tri is not None:
        out["triangulation"] = tri.records()
    return out


def _cell(value: float, width: int = 11) -> str:
    return f"{'inf':>{width}}" if math.isinf(value) else f"{value:>{width}.3f}"


def format_table(camera, slices, views, gaps, check, path, tri=None) -> str:
    """A readable table in the layout of the paper's Tables 2 and 4 (slices in the optics' object space)."""
    optics = camera.main_optics
    space = slices.space
    pupil = ("exit pupil at infinity (telecentric)" if camera.telecentric else
             f"exit pupil {optics.exit_pupil_distance_mm:.3f} mm from the MLA (micro images scaled by "
             f"{camera.micro_image_scale:.6f}, samples {camera.sample_pitch_mm * 1e3:.3f} µm apart)")
    out = [f"camera {camera.name or path}: {optics.describe()}, m = {camera.m_hat} px per micro image, effective "
           f"pixel pitch {camera.effective_pixel_pitch_mm * 1e3:.3f} µm, {pupil}"]
    if camera.provenance:
        out.append("where the camera's numbers came from:")
        out += [f"  {key}: {text}" for key, text in camera.provenance]
    out += [f"positions [{space.symbol}] {space.origin}",
            f"{'a':>8} {'near':>11} {space.letter:>11} {'far':>11} {'DOF':>11}"]
    for r in slices.records():
        position, near, far, dof = (r[k] for k in space.keys)
        out.append(f"{r['a']:>8g} {_cell(near)} {_cell(position)} {_cell(far)} {_cell(dof)}")
    for a, lo, hi in gaps:
        out.append(f"  gap between a = {a:g} and {a + 1:g}: {lo:.3f} .. {hi:.3f} {space.symbol} is in no integer "
                   f"slice's DOF")
    out.append("")
    if views.baseline_mm is not None:
        out.append(f"views (Eqs. 17, 33): baseline of adjacent views {views.baseline_mm:.4f} mm")
        out.append(f"{'i':>5} {'position F_i [mm]':>18} {'tilt [deg]':>11}")
        out += [f"{r['i']:>5d} {r['position_mm']:>18.4f} {r['tilt_deg']:>11.4f}" for r in views.records()]
    else:
        from .. import geometry
        shifts = "paraxial" if geometry.refocus_slopes(camera) is None else "aplanatic (sine condition)"
        out.append(f"views: orthographic, object-space angle (sine condition); {views.lateral_sampling_um:.4g} um per "
                   f"lens in the object; {shifts} per-view refocus shifts")
        out.append(f"{'i':>5} {'angle [deg]':>12} {'inside':>10}")
        for r in views.records():
            angle = "-" if r["angle_deg"] is None else f"{r['angle_deg']:.3f}"
            out.append(f"{r['i']:>5d} {angle:>12} {'yes' if r['inside_na'] else 'no':>10}")
    if tri is not None:
        out.append("")
        out.append("triangulation (PlenoptiSign's G and dx; distance from the sensor)")
        out.append(f"{'G':>5} {'dx [px]':>9} {'B_G [mm]':>10} {'tilt [deg]':>11} {'distance':>11}")
        for r in tri.records():
            out.append(f"{r['gap']:>5} {r['disparity_px']:>9g} {r['baseline_mm']:>10.4f} {r['tilt_deg']:>11.4f} "
                       f"{_cell(r['distance_mm'])}")
    if check is not None:
        out.append("")
        out.append(check.message())
    return "\n".join(out) + "\n"
