"""``lfproc viewer``: a static page per capture to refocus by clicking and read distances in metres."""

from __future__ import annotations

import os

from ..errors import LfprocError
from .capture_loop import add_decode_options, for_each_capture, require_output_folder, setup_from_args
from .common import add_slice_planning_options, slice_parameters


def register(sub) -> None:
    p = sub.add_parser("viewer", help="write a browser viewer: click to refocus, drag to move the viewpoint",
                       description="Decode each capture and write a self-contained static viewer into OUTDIR "
                                   "(index.html, its 8-bit sRGB images and geometry.json): the refocused stack, "
                                   "click a point to show the slice sharpest there with its distance and depth of "
                                   "field in metres, drag or use the arrow keys to move the viewpoint, a depth map "
                                   "with its legend, the camera and calibration. Opens from the file system; no "
                                   "network access. Several captures: one page each in OUTDIR/STEM/ plus an index.")
    p.add_argument("raw", nargs="+", metavar="INPUT", help="raw captures (as lfproc refocus takes them)")
    add_decode_options(p)
    which = p.add_mutually_exclusive_group()
    which.add_argument("--a", metavar="LIST", help="show these slices instead of those planned for the scene")
    which.add_argument("--depth-range", metavar="NEAR_MM:FAR_MM",
                       help="show the fewest slices whose depths of field cover this range (default: planned for "
                            "the depths the scene shows, found by depth from focus)")
    add_slice_planning_options(p)
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR")
    p.add_argument("--upscale", default="nearest", choices=("nearest", "smooth"),
                   help="how the page enlarges the images (one pixel per lens) to --display-size: nearest keeps "
                        "every lens a sharp block (default), smooth interpolates")
    p.add_argument("--display-size", type=int, default=512, metavar="PX",
                   help="smallest long side of the shown pictures in screen pixels (default 512)")
    p.add_argument("--serve", action="store_true", help="then serve OUTDIR on 127.0.0.1 and print the URL")
    p.add_argument("--port", type=int, default=8000, help="port for --serve (default 8000; 0 = any free port)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..camera import Camera
    from ..pipeline import load_lightfield, unique_stems
    from ..viewer import PageOptions, build_page, calibration_summary, make_server, page_entry, write_index

    if (args.max_gap or args.integer) and args.depth_range is None:
        raise LfprocError("--max-gap and --integer apply to --depth-range only")
    if args.display_size < 16:
        raise LfprocError(f"--display-size must be at least 16 px, got {args.display_size}")
    require_output_folder(args.outdir)
    server = make_server(args.outdir if os.path.isdir(args.outdir) else ".", args.port) if args.serve else None
    if server is not None:
        server.server_close()  # the port is free: checked before any work, bound again after it
    camera = Camera.from_toml(args.camera)
    a_values = None
    if args.a is not None or args.depth_range is not None:
        a_values = slice_parameters(camera, args.a, args.depth_range, None, args.max_gap, args.integer)
    setup = setup_from_args(args, camera)
    stems = unique_stems(args.raw)
    several = len(args.raw) > 1
    options = PageOptions(min_long_side=args.display_size, upscale=args.upscale)
    calibration = calibration_summary(setup.grid, getattr(setup.white, "source", None))
    pages = {}

    def work(path, progress):
        lf = load_lightfield(path, setup)
        folder = os.path.join(args.outdir, stems[path]) if several else args.outdir
        pages[path] = build_page(lf, folder, source=os.path.abspath(path), stem=stems[path], a_values=a_values,
                                 calibration=calibration, index_href="../index.html" if several else None,
                                 options=options)
        progress.update(1)

    status = for_each_capture("viewer", args.raw, work)
    if several and pages:
        index = write_index(args.outdir, [page_entry(args.outdir, os.path.dirname(pages[p]))
                                          for p in args.raw if p in pages])
    else:
        index = next(iter(pages.values()), None)
    if index is None:
        return status
    print(f"viewer: {os.path.abspath(index)}")
    if args.serve:
        from ..viewer import serve

        serve(os.path.abspath(args.outdir), args.port)
    return status
