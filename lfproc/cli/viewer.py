"""``lfproc viewer``: a static page per capture to refocus by clicking and read distances in metres."""

from __future__ import annotations

import os

from ..errors import LfprocError
from .capture_loop import add_decode_options, add_output_folder_option, for_each_capture, input_camera, \
    prepare_inputs, require_output_folder
from .common import add_aperture_option, add_slice_options, aperture_extent, check_slice_options, slice_parameters
from .refocus import check_view_coverage, summed_extent


def register(sub) -> None:
    p = sub.add_parser("viewer", help="write a browser viewer: click to refocus, drag to move the viewpoint",
                       description="Decode each capture and write a self-contained static viewer into OUTDIR "
                                   "(index.html, its 8-bit sRGB images and geometry.json): the refocused stack; "
                                   "click a point to show the slice sharpest there with its distance and depth of "
                                   "field in metres; drag or use the arrow keys to move the viewpoint; a depth map "
                                   "with its legend; the camera and calibration. Opens from the file system, no "
                                   "network access. Several captures: one page each in OUTDIR/STEM/ plus an index. "
                                   "Without --a/--depth-range/--at the slices are planned for the depths the scene "
                                   "shows (its depth map, as lfproc depth computes it).")
    p.add_argument("capture", nargs="+", metavar="INPUT",
                   help="captures (camera raw, TIFF/PNG/EXR, Lytro) or light fields from lfproc decode (.lfp.npz); "
                        "processed Lytro pictures get a page of their focus stack")
    add_decode_options(p)
    add_slice_options(p)
    add_output_folder_option(p)
    p.add_argument("--upscale", default="smooth", choices=("smooth", "nearest"),
                   help="how the page enlarges its slices and views (one pixel per lens) to --display-size: smooth "
                        "lets the browser interpolate (default), nearest keeps every lens a sharp block; the depth "
                        "map always shows its lenses as blocks (an unknown lens stays grey)")
    p.add_argument("--display-size", type=int, default=512, metavar="PX",
                   help="smallest long side of the shown pictures in screen pixels (default 512)")
    p.add_argument("--serve", action="store_true", help="then serve OUTDIR on 127.0.0.1 and print the URL")
    p.add_argument("--port", type=int, default=8000, help="port for --serve (default 8000; 0 = any free port)")
    add_aperture_option(p)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..outputs import unique_stems
    from ..viewer import PageOptions, build_page, calibration_summary, make_server, page_entry, write_index
    from ..viewpoints import with_aperture

    if _pictures(args):
        return 0
    check_slice_options(args)
    if args.display_size < 16:
        raise LfprocError(f"--display-size must be at least 16 px, got {args.display_size}")
    require_output_folder(args.outdir)
    if args.serve:
        make_server(".", args.port).server_close()  # the port is free: checked before any work
    stems = unique_stems(args.capture)
    camera = input_camera(args, args.capture)
    chosen = (args.a is not None or args.depth_range_mm is not None or args.distance_mm is not None
              or args.z_range_um is not None)
    extent = aperture_extent(camera, args.aperture)   # an impossible --aperture fails before any work
    if chosen:  # every list is checked before any capture is read
        slice_parameters(camera, args.a, args.depth_range_mm, args.distance_mm, args.max_gap, args.integer,
                         max_slices=args.max_slices, view_extent=extent, z_range=args.z_range_um)
    inputs = prepare_inputs(args, args.capture, camera)   # calibration last: every cheap check fails first
    several = len(args.capture) > 1
    options = PageOptions(min_long_side=args.display_size, upscale=args.upscale)
    pages = {}

    def work(path, progress):
        lf = with_aperture(inputs.load(path), args.aperture)
        a_values = None
        if chosen:
            a_values = slice_parameters(lf.camera, args.a, args.depth_range_mm, args.distance_mm, args.max_gap,
                                        args.integer, max_slices=args.max_slices, z_range=args.z_range_um,
                                        view_extent=summed_extent(lf.camera, args.aperture, lf.view_mask))
            check_view_coverage(lf.camera, a_values, lf.lens_shape, path, lf.view_mask)
        folder = os.path.join(args.outdir, stems[path]) if several else args.outdir
        grid = lf.grid if lf.grid is not None else getattr(inputs.setup, "grid", None)
        white = getattr(inputs.setup, "white_path", None)
        pages[path] = build_page(lf, folder, source=os.path.abspath(path), stem=stems[path], a_values=a_values,
                                 calibration=calibration_summary(grid, white),
                                 index_href="../index.html" if several else None, options=options)
        progress.update(1)
        print(f"{path}: viewer page -> {pages[path]}")

    status = for_each_capture("viewer", args.capture, work)
    if several and pages:
        index = write_index(args.outdir, [page_entry(args.outdir, os.path.dirname(pages[p]))
                                          for p in args.capture if p in pages])
    else:
        index = next(iter(pages.values()), None)
    if index is None:
        return status
    print(f"viewer: {os.path.abspath(index)}")
    if args.serve:
        serve_until_interrupted(os.path.abspath(args.outdir), args.port)
    return status


def _pictures(args) -> bool:
    """Processed Lytro pictures get a focus stack page (``viewer/_picture.py``); True when they were the inputs."""
    from ..io import is_picture_file

    pictures = [path for path in args.capture if os.path.isfile(path) and is_picture_file(path)]
    if not pictures:
        return False
    if len(pictures) != len(args.capture):
        raise LfprocError(f"{pictures[0]}: a processed Lytro picture among captures; view pictures and captures in "
                          f"separate runs")
    from ..outputs import unique_stems
    from ..viewer import build_picture_pages, make_server

    require_output_folder(args.outdir)
    if args.serve:
        make_server(".", args.port).server_close()
    index = build_picture_pages(args.capture, args.outdir, unique_stems(args.capture))
    print(f"viewer: {os.path.abspath(index)}")
    if args.serve:
        serve_until_interrupted(os.path.abspath(args.outdir), args.port)
    return True


def serve_until_interrupted(folder: str, port: int) -> None:
    """Serve ``folder`` (:func:`lfproc.viewer.serve`), print its address, and stop at Ctrl-C."""
    import sys
    import threading

    from ..viewer import serve

    server = serve(folder, port)
    print(f"serving {folder} at {server.url} (Ctrl-C to stop)", flush=True)
    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)
    finally:
        server.shutdown()
        server.server_close()
