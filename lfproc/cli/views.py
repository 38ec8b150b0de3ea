"""``lfproc views``: the viewpoint images of captures (Eq. 32), each tagged with position and tilt."""

from __future__ import annotations

from .capture_loop import add_decode_options, add_output_folder_option, for_each_capture, input_camera, \
    prepare_inputs, require_output_folder
from .common import FORMAT_HELP, add_preview_option, preview_format


def register(sub) -> None:
    p = sub.add_parser("views", help="extract the viewpoint images of captures",
                       description="Decode each capture and write one image per view with a sidecar (source, view "
                                   "[ky, kx], position_mm [y, x], tilt_deg [y, x]), the same embedded in the image.")
    p.add_argument("capture", nargs="+", metavar="RAW",
                   help="captures (camera raw, TIFF/PNG/EXR, Lytro) or light fields from lfproc decode (.lfp.npz)")
    add_decode_options(p)
    add_output_folder_option(p)
    p.add_argument("--format", default="tiff", choices=("tiff", "png16", "jpeg", "exr"), help=FORMAT_HELP)
    add_view_options(p)
    p.set_defaults(func=run)


def add_view_options(p) -> None:
    """The per-capture options of views besides --format (also offered by batch)."""
    p.add_argument("--mosaic", action="store_true",
                   help="also one image tiling the views that carry light, and its labelled preview PNG")
    p.add_argument("--gif", action="store_true", help="also an animation walking the views along a circle")
    p.add_argument("--inside-aperture", action="store_true",
                   help="only the views inside the main lens aperture (needs main_lens.f_number; a microscope's: "
                        "its NA); the mosaic "
                        "shows the others black")
    add_preview_option(p, "each view")


def check_view_options(args, camera) -> None:
    from ..errors import LfprocError

    if args.inside_aperture and camera.main_optics.image_aperture_sine is None:   # no f-number (nor NA)
        raise LfprocError(f"{camera.source or 'camera'}: --inside-aperture needs main_lens.f_number in the camera "
                          f"file")


def run(args) -> int:
    from .. import geometry
    from ..api import view_stack
    from ..outputs import shown_views
    from ..outputs import unique_stems

    require_output_folder(args.outdir)
    stems = unique_stems(args.capture)
    camera = input_camera(args, args.capture)
    check_view_options(args, camera)
    inputs = prepare_inputs(args, args.capture, camera)
    per_capture = int(geometry.views_inside_aperture(camera).sum()) if args.inside_aperture else camera.m_hat ** 2

    def work(path, progress):
        lf = inputs.load(path)
        check_view_options(args, lf.camera)
        written = view_stack(lf, inside_aperture=args.inside_aperture).save(
            args.outdir, stems[path], format=args.format, mosaic=args.mosaic, gif=args.gif, preview=preview_format(args))
        progress.update(per_capture)
        shown = shown_views(lf, args.inside_aperture)
        print(f"{path}: {shown.summary()}; {len(written)} file(s) -> {args.outdir}/{stems[path]}_*")

    return for_each_capture("views", args.capture, work, total_steps=len(args.capture) * per_capture)
