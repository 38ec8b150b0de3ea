"""``lfproc refocus``: refocused slices of raw captures, each tagged with its distance and depth of field."""

from __future__ import annotations

import os

from ..errors import LfprocError
from .capture_loop import add_decode_options, for_each_capture, require_output_folder, setup_from_args
from .common import add_slice_planning_options, slice_parameters


def register(sub) -> None:
    p = sub.add_parser("refocus", help="refocus captures at given a, distance or depth range",
                       description="Decode each capture once and render all its slices (Eq. 9). Each slice is "
                                   "written with a sidecar (source, a, distance_mm, near_mm, far_mm, dof_mm), the "
                                   "same fields embedded in the image metadata.")
    p.add_argument("raw", nargs="+", metavar="RAW", help="raw captures")
    add_decode_options(p)
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--a", metavar="LIST", help="refocus parameters: numbers and ranges START:STOP[:STEP]")
    which.add_argument("--depth-range", metavar="NEAR_MM:FAR_MM",
                       help="render the fewest slices whose depths of field cover this range (FAR may be inf)")
    which.add_argument("--at", metavar="DISTANCE_MM", type=float, help="the slice focused at this distance")
    add_slice_planning_options(p)
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR")
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"),
                   help="tiff = float32 linear (default), png16 = 16-bit linear, jpeg = 8-bit sRGB preview, exr")
    p.add_argument("--interpolation", default="linear", choices=("nearest", "linear", "cubic"),
                   help="interpolation between lenses for real a (default linear)")
    p.add_argument("--upsample", type=int, default=1, help="spatial upsampling factor of the slices (default 1)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..camera import Camera
    from ..outputs import write_slices
    from ..pipeline import load_lightfield, unique_stems
    from ..refocus import refocus

    if args.upsample < 1:
        raise LfprocError(f"--upsample must be an integer >= 1, got {args.upsample}")
    if (args.max_gap or args.integer) and args.depth_range is None:
        raise LfprocError("--max-gap and --integer apply to --depth-range only")
    require_output_folder(args.outdir)
    camera = Camera.from_toml(args.camera)
    a_values = slice_parameters(camera, args.a, args.depth_range, args.at, args.max_gap, args.integer)
    setup = setup_from_args(args, camera)  # calibration last: every cheap check fails first
    stems = unique_stems(args.raw)

    def work(path, progress):
        lf = load_lightfield(path, setup)
        stack = refocus(lf, a_values, interpolation=args.interpolation, upsample=args.upsample)
        write_slices(args.outdir, stems[path], os.path.abspath(path), setup.camera, a_values, stack, args.format)
        progress.update(len(a_values))

    return for_each_capture("refocus", args.raw, work, total_steps=len(args.raw) * len(a_values))
