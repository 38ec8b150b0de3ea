"""``lfproc views``: the viewpoint images of raw captures (Eq. 32), each tagged with position and tilt."""

from __future__ import annotations

import os

from .capture_loop import add_decode_options, for_each_capture, require_output_folder, setup_from_args


def register(sub) -> None:
    p = sub.add_parser("views", help="extract the viewpoint images of captures",
                       description="Decode each capture and write one image per view with a sidecar (source, view "
                                   "[ky, kx], position_mm [y, x], tilt_deg [y, x]), the same embedded in the image.")
    p.add_argument("raw", nargs="+", metavar="RAW", help="raw captures")
    add_decode_options(p)
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR")
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"))
    p.add_argument("--mosaic", action="store_true", help="also one image tiling all views")
    p.add_argument("--gif", action="store_true", help="also an animation walking the views along a circle")
    p.add_argument("--inside-aperture", action="store_true",
                   help="only the views inside the main lens aperture (needs main_lens.f_number); "
                        "the mosaic shows the others black")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import geometry
    from ..camera import Camera
    from ..errors import LfprocError
    from ..outputs import write_view_gif, write_view_mosaic, write_views
    from ..pipeline import load_lightfield, unique_stems

    require_output_folder(args.outdir)
    camera = Camera.from_toml(args.camera)
    if args.inside_aperture and camera.f_number is None:
        raise LfprocError(f"{args.camera}: --inside-aperture needs main_lens.f_number in the camera file")
    setup = setup_from_args(args, camera)
    keep = geometry.views_inside_aperture(setup.camera)
    stems = unique_stems(args.raw)
    per_capture = int(keep.sum()) if args.inside_aperture else setup.camera.m_hat ** 2

    def work(path, progress):
        lf = load_lightfield(path, setup)
        source = os.path.abspath(path)
        write_views(args.outdir, stems[path], source, setup.camera, lf.views, args.format,
                    keep if args.inside_aperture else None)
        if args.mosaic:
            write_view_mosaic(args.outdir, stems[path], source, setup.camera, lf.views, args.format,
                              keep if args.inside_aperture else None)
        if args.gif:
            write_view_gif(args.outdir, stems[path], lf.views, keep)
        progress.update(per_capture)

    return for_each_capture("views", args.raw, work, total_steps=len(args.raw) * per_capture)
