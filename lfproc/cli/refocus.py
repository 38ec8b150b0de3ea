"""``lfproc refocus``: refocused slices of captures, each tagged with its distance and depth of field."""

from __future__ import annotations

import os

from ..api import DEFAULT_INTERPOLATION
from ..errors import LfprocError
from .capture_loop import add_decode_options, add_output_folder_option, for_each_capture, input_camera, \
    prepare_inputs, require_output_folder
from .common import FORMAT_HELP, INTERPOLATION_HELP, add_aperture_option, add_preview_option, add_slice_options, \
    aperture_extent, check_slice_options, describe_slices, preview_format, slice_parameters


def register(sub) -> None:
    p = sub.add_parser("refocus", help="refocus captures at given a, distance or depth range",
                       description="Decode each capture once and render all its slices (Eq. 9). Each slice is "
                                   "written with a sidecar (source, a, distance_mm, near_mm, far_mm, dof_mm), the "
                                   "same fields embedded in the image metadata. Prints one line per slice: a, the "
                                   "distance it focuses at and its depth of field.")
    p.add_argument("capture", nargs="+", metavar="RAW",
                   help="captures (camera raw, TIFF/PNG/EXR, Lytro) or light fields from lfproc decode (.lfp.npz)")
    add_decode_options(p)
    add_slice_options(p).required = True
    add_output_folder_option(p)
    add_render_options(p)
    add_aperture_option(p)
    add_preview_option(p, "each slice, labelled with its distance and DOF")
    p.set_defaults(func=run)


def add_render_options(p) -> None:
    """``--format``, ``--interpolation``, ``--upsample`` and ``--stack`` of refocused slices (refocus and batch)."""
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"), help=FORMAT_HELP)
    p.add_argument("--interpolation", default=DEFAULT_INTERPOLATION,
                   choices=("nearest", "linear", "cubic", "cubic-sharp", "cubic-spline"),
                   help=INTERPOLATION_HELP)
    p.add_argument("--upsample", type=int, default=1, metavar="S",
                   help="render slices on an S times finer grid than the lenses (default 1: one pixel per lens)")
    p.add_argument("--stack", choices=("imagej", "ome"),
                   help="also write all slices of a capture as one z-stack file, STEM_stack.tif (imagej: an ImageJ "
                        "hyperstack) or STEM_stack.ome.tif (ome: OME-TIFF), with the physical x/y/z spacing in µm "
                        "for a microscope (Fiji and napari open it to scale) and each slice's a and distance "
                        "for a photographic camera")


def check_render_options(args) -> None:
    if args.upsample < 1:
        raise LfprocError(f"--upsample must be an integer >= 1, got {args.upsample}")


def run(args) -> int:
    from ..api import focal_stack
    from ..outputs import unique_stems
    from ..viewpoints import with_aperture

    check_render_options(args)
    check_slice_options(args)
    require_output_folder(args.outdir)
    stems = unique_stems(args.capture)
    camera = input_camera(args, args.capture)
    plans, described = {}, set()

    def slices_for(camera, view_mask=None):
        """The slices for this camera and these summed views (their DOF plans --depth-range)."""
        extent = summed_extent(camera, args.aperture, view_mask)
        key = (camera.to_toml(), extent)
        if key not in plans:
            plans[key] = slice_parameters(camera, args.a, args.depth_range_mm, args.distance_mm, args.max_gap,
                                          args.integer, max_slices=args.max_slices, view_extent=extent,
                                          z_range=args.z_range_um)
        return key, plans[key]

    def describe_once(key, camera, values, view_mask):
        """The slice table, printed when the first capture with this camera has rendered."""
        if key not in described:
            described.add(key)
            describe_slices(camera, values, args.depth_range_mm, max_gap_mm=args.max_gap, integer=args.integer,
                            max_slices=args.max_slices, view_mask=view_mask)

    a_values = slices_for(camera)[1]   # every list (and --aperture) is checked before any capture is read
    inputs = prepare_inputs(args, args.capture, camera)   # calibration last: every cheap check fails first

    def work(path, progress):
        lf = with_aperture(inputs.load(path), args.aperture)
        key, values = slices_for(lf.camera, lf.view_mask)
        stack = focal_stack(lf, a=values, interpolation=args.interpolation, upsample=args.upsample)
        describe_once(key, lf.camera, values, lf.view_mask)
        written = stack.save(args.outdir, stems[path], format=args.format, preview=preview_format(args),
                             stack=args.stack)
        stack_file = written[-1] if args.stack else None      # save returns the slices, previews, then the stack
        progress.update(len(values))
        print(f"{path}: {len(values)} slice(s) -> {os.path.dirname(written[0]) or '.'}/{stems[path]}_*"
              + (f"; z-stack -> {stack_file}" if stack_file else ""))

    return for_each_capture("refocus", args.capture, work, total_steps=len(args.capture) * len(a_values))


def summed_extent(camera, aperture, view_mask=None):
    """The DOF extent of the views a slice sums: the light field's (``view_mask``), else ``--aperture``'s."""
    if view_mask is not None:
        from ..geometry import summed_view_extent

        return summed_view_extent(view_mask)
    return aperture_extent(camera, aperture)


def check_view_coverage(camera, a_values, lens_shape, source: str, view_mask=None) -> None:
    """:func:`lfproc.api.check_view_coverage` (refuse a garbage a, warn where most pixels miss some views)."""
    from ..api import check_view_coverage as check

    check(camera, a_values, lens_shape, source, view_mask)
