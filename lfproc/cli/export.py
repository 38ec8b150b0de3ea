"""``lfproc export``: the focus stack, perspective views and depth map of processed Lytro pictures."""

from __future__ import annotations

import os


def register(sub) -> None:
    p = sub.add_parser("export", help="write a processed Lytro picture's focus stack and depth map (in mm)",
                       description="For each processed Lytro picture (first generation NAME-stk.lfp / NAME-dm.lfp, "
                                   "Illum .LFP from the camera or Lytro Desktop): every focus stack image as the "
                                   "JPEG it is (and, with --tiff, as linear float TIFF) with its lambda and, where "
                                   "the camera is known (the picture's metadata, or --camera), the refocus "
                                   "parameter a, distance and depth of field from the sensor (derived from lambda and "
                                   "the camera's f-number and lens pitch); each perspective view of an edofParallax block with its aperture "
                                   "coordinate (--views-jpeg, --wobble for pictures to share); the depth map in "
                                   "lambda (STEM_depth_lambda.tif) and, where the camera is known, in mm "
                                   "(STEM_depth.tif) with a preview in metres (in lambda otherwise). Every image gets "
                                   "a NAME.json sidecar and embedded metadata.")
    p.add_argument("pictures", nargs="+", metavar="PICTURE", help="processed Lytro pictures (.lfp/.lfr/.LFP)")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                   help="folder for the outputs (created if missing); every image gets a NAME.json sidecar")
    p.add_argument("--tiff", action="store_true",
                   help="also write each stack image as linear float32 TIFF (the sRGB JPEG decoded and linearised)")
    p.add_argument("--camera", metavar="CAM.toml",
                   help="the camera, for pictures whose metadata does not describe it (first-generation stacks) or "
                        "to override it: its f_number, lens pitch and b_U turn lambda into a and mm (e.g. a camera "
                        "file from 'lfproc camera' on a Lytro file of the same camera)")
    p.add_argument("--focus-distance", dest="focus_distance_mm", type=float, metavar="MM",
                   help="distance from the sensor the main lens was focused at (mm): b_U by the thin-lens equation "
                        "instead of the metadata's infinityLambda or the camera file's b_U")
    p.add_argument("--views-jpeg", action="store_true",
                   help="also write each perspective view as an sRGB JPEG (STEM_parallax_KK.jpg)")
    p.add_argument("--wobble", action="store_true",
                   help="also write STEM_wobble.gif, the perspective views walked around the aperture")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..errors import LfprocError
    from ..io import existing_file, has_container_extension, is_container
    from ..outputs import export_picture
    from ..outputs import unique_stems
    from .capture_loop import require_output_folder

    require_output_folder(args.outdir)   # before any input is read
    camera = None
    if args.focus_distance_mm is not None and not (args.focus_distance_mm > 0):
        raise LfprocError(f"--focus-distance must be a positive distance in mm (inf allowed), got "
                          f"{args.focus_distance_mm:g}")
    if args.camera is not None:
        from ..camera import Camera
        from ..io import camera_lambda_map

        camera = Camera.from_toml(existing_file(args.camera))
        camera_lambda_map(camera, args.camera)    # a camera that cannot map lambda fails before any work
    for path in args.pictures:   # cheap checks on every input before any work
        existing_file(path)
        if not (has_container_extension(path) or is_container(path)):
            raise LfprocError(f"{path}: not a Lytro picture (.lfp/.lfr container); lfproc export reads processed "
                              f"Lytro pictures, use lfproc refocus/views/depth for captures")
    if args.focus_distance_mm is not None and camera is None:   # every picture must know its camera: before any output
        from ..io import open_picture, picture_lambda_map

        for path in args.pictures:
            _, mapping, why = picture_lambda_map(open_picture(path))
            if mapping is None:
                raise LfprocError(f"{path}: --focus-distance needs the camera, and this picture's metadata does not "
                                  f"describe it ({why}); add --camera CAM.toml (e.g. from 'lfproc camera' on a Lytro "
                                  f"file of the same camera)")
    stems = unique_stems(args.pictures)
    for path in args.pictures:
        written = export_picture(path, args.outdir, stems[path], tiff=args.tiff, camera=camera,
                                 camera_path=args.camera, focus_distance_mm=args.focus_distance_mm,
                                 views_jpeg=args.views_jpeg, wobble=args.wobble)
        print(f"{path}: {len(written)} images -> {os.path.abspath(args.outdir)}")
    return 0
