"""``lfproc refocus``: refocused slices of captures, each tagged with its distance and depth of field."""

from __future__ import annotations

import os

from ..errors import LfprocError
from .capture_loop import add_decode_options, add_output_folder_option, for_each_capture, input_camera, \
    prepare_inputs, require_output_folder
from .common import FORMAT_HELP, INTERPOLATION_HELP, add_slice_options, check_slice_options, describe_slices, \
    slice_parameters


def register(sub) -> None:
    p = sub.add_parser("refocus", help="refocus captures at given a, distance or depth range",
                       description="Decode each capture once and render all its slices (Eq. 9). Each slice is "
                                   "written with a sidecar (source, a, distance_mm, near_mm, far_mm, dof_mm), the "
                                   "same fields embedded in the image metadata. Prints one line per slice: a, the "
                                   "distance it focuses at and its depth of field.")
    p.add_argument("raw", nargs="+", metavar="RAW",
                   help="captures (camera raw, TIFF/PNG/EXR, Lytro) or light fields from lfproc decode (.lfp.npz)")
    add_decode_options(p)
    add_slice_options(p).required = True
    add_output_folder_option(p)
    add_render_options(p)
    p.set_defaults(func=run)


def add_render_options(p) -> None:
    """``--format``, ``--interpolation``, ``--upsample`` and ``--stack`` of refocused slices (refocus and batch)."""
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"), help=FORMAT_HELP)
    p.add_argument("--interpolation", default="cubic-sharp", choices=("nearest", "linear", "cubic", "cubic-sharp"),
                   help=INTERPOLATION_HELP)
    p.add_argument("--upsample", type=int, default=1, metavar="S",
                   help="render slices on an S times finer grid than the lenses (default 1)")
    p.add_argument("--stack", choices=("imagej", "ome"),
                   help="also write all slices of a capture as one z-stack file, STEM_stack.tif (imagej: an ImageJ "
                        "hyperstack) or STEM_stack.ome.tif (ome: OME-TIFF), with the physical x/y/z spacing in µm "
                        "for a microscope (Fiji and napari open it to scale) and each slice's a and distance "
                        "for a photographic camera")


def check_render_options(args) -> None:
    if args.upsample < 1:
        raise LfprocError(f"--upsample must be an integer >= 1, got {args.upsample}")


def run(args) -> int:
    from ..outputs import lateral_um_per_lens, slice_metadata, stack_path, write_focal_stack, write_slices
    from ..pipeline import unique_stems
    from ..refocus import refocus

    check_render_options(args)
    check_slice_options(args)
    require_output_folder(args.outdir)
    stems = unique_stems(args.raw)
    camera = input_camera(args, args.raw)
    plans, described = {}, set()

    def slices_for(camera):
        key = camera.to_toml()
        if key not in plans:
            plans[key] = slice_parameters(camera, args.a, args.depth_range, args.at, args.max_gap, args.integer,
                                          max_slices=args.max_slices, z_range=args.z_range)
        return key, plans[key]

    def describe_once(key, camera, values):
        """The slice table, printed when the first capture with this camera has rendered."""
        if key not in described:
            described.add(key)
            describe_slices(camera, values, args.depth_range, max_gap_mm=args.max_gap, integer=args.integer,
                            max_slices=args.max_slices)

    a_values = slices_for(camera)[1]   # every list is checked before any capture is read
    inputs = prepare_inputs(args, args.raw, camera)   # calibration last: every cheap check fails first

    def work(path, progress):
        lf = inputs.load(path)
        key, values = slices_for(lf.camera)
        check_view_coverage(lf.camera, values, lf.lens_shape, path)
        stack = refocus(lf, values, interpolation=args.interpolation, upsample=args.upsample)
        describe_once(key, lf.camera, values)
        written = write_slices(args.outdir, stems[path], os.path.abspath(path), lf.camera, values, stack,
                               args.format)
        if args.stack:
            write_focal_stack(stack_path(args.outdir, stems[path], args.stack), stack,
                              slice_metadata(os.path.abspath(path), lf.camera, values), kind=args.stack,
                              lens_um=lateral_um_per_lens(lf.camera), upsample=args.upsample)
        progress.update(len(values))
        print(f"{path}: {len(written)} slice(s) -> {os.path.dirname(written[0]) or '.'}/{stems[path]}_a*")

    return for_each_capture("refocus", args.raw, work, total_steps=len(args.raw) * len(a_values))


def check_view_coverage(camera, a_values, lens_shape, source: str) -> None:
    """Refuse slices that fewer than half the views reach (a garbage a); warn where most pixels miss some."""
    import warnings

    from .. import geometry
    from ..refocus import MIN_OVERLAPPING_VIEWS, full_view_fraction, max_usable_a, overlapping_view_fraction
    from .common import _mm

    m, (ny, nx) = camera.m_hat, lens_shape
    reached = overlapping_view_fraction(a_values, m, lens_shape)
    beyond = [a for a, f in zip(a_values, reached) if f < MIN_OVERLAPPING_VIEWS]
    if beyond:
        limit = max_usable_a(m, lens_shape)
        if camera.is_microscope:
            near, far = (f"{z:.4g} um" for z in geometry.slice_geometry(camera, [limit, -limit]).z_um)
        else:
            near, far = (_mm(float(d)) for d in geometry.slice_distance_mm(camera, [limit, -limit]))
        share = float(overlapping_view_fraction(beyond[0], m, lens_shape))
        raise LfprocError(f"{source}: at a={beyond[0]:g} only {100 * share:.0f} % of the {m}x{m} views reach this "
                          f"{ny}x{nx}-lens capture (the others shift off it); refocus within |a| < {limit:.3g}, i.e. "
                          f"from {near} (a=+{limit:.3g}) to {far} (a=-{limit:.3g})")
    share = full_view_fraction(a_values, m, lens_shape)
    thin = [a for a, f in zip(a_values, share) if f < 0.5]
    if thin:
        worst = max(thin, key=abs)
        warnings.warn(f"{source}: in {len(thin)} slice(s) (up to a={worst:+.3g}) fewer than half the pixels average "
                      f"all views: a border band of up to {abs(worst) * (m - 1) / 2:.0f} lenses is less refocused")
