"""``lfproc export``: the focus stack, perspective views and depth map of processed Lytro pictures."""

from __future__ import annotations

import os


def register(sub) -> None:
    p = sub.add_parser("export", help="write a processed Lytro picture's focus stack and depth map (in mm)",
                       description="For each processed Lytro picture (first generation NAME-stk.lfp / NAME-dm.lfp, "
                                   "Illum .LFP from the camera or Lytro Desktop): every focus stack image as the "
                                   "JPEG it is (and, with --tiff, as linear float TIFF) with its lambda and, where "
                                   "the picture's metadata describes the camera, the refocus parameter a, distance "
                                   "and depth of field from the sensor (derived from lambda: the README's Lytro section); each "
                                   "perspective view of an edofParallax block with its aperture coordinate; the "
                                   "depth map in lambda (STEM_depth_lambda.tif) and in mm (STEM_depth.tif) with a "
                                   "preview in metres. Every image gets a NAME.json sidecar and embedded metadata.")
    p.add_argument("pictures", nargs="+", metavar="PICTURE", help="processed Lytro pictures (.lfp/.lfr/.LFP)")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                   help="folder for the outputs (created if missing); every image gets a NAME.json sidecar")
    p.add_argument("--tiff", action="store_true",
                   help="also write each stack image as linear float32 TIFF (the sRGB JPEG decoded and linearised)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..errors import LfprocError
    from ..io import existing_file, has_container_extension, is_container
    from ..outputs import export_picture
    from ..pipeline import unique_stems
    from .capture_loop import require_output_folder

    require_output_folder(args.outdir)   # before any input is read
    for path in args.pictures:   # cheap checks on every input before any work
        existing_file(path)
        if not (has_container_extension(path) or is_container(path)):
            raise LfprocError(f"{path}: not a Lytro picture (.lfp/.lfr container); lfproc export reads processed "
                              f"Lytro pictures, use lfproc refocus/views/depth for captures")
    stems = unique_stems(args.pictures)
    for path in args.pictures:
        written = export_picture(path, args.outdir, stems[path], tiff=args.tiff)
        print(f"{path}: {len(written)} images -> {os.path.abspath(args.outdir)}")
    return 0
