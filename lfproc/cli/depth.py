"""``lfproc depth``: metric depth maps (mm), their confidence and an all-in-focus image of raw captures."""

from __future__ import annotations

import os

from .capture_loop import add_decode_options, for_each_capture, require_output_folder, setup_from_args
from .common import parse_depth_range


def register(sub) -> None:
    p = sub.add_parser("depth", help="depth map in mm, confidence and all-in-focus image of each capture",
                       description="Decode each capture and estimate the distance from the sensor of the surface "
                                   "seen at every lens (a plane sweep over the refocus parameter a, mapped to mm by "
                                   "the paper's geometry). Writes STEM_depth.tif (float32 mm, NaN = unknown), "
                                   "STEM_depth_confidence.tif, STEM_allfocus.tif, STEM_depth_preview.png and "
                                   "STEM_depth_points.ply, each with a sidecar; the same metadata embedded.")
    p.add_argument("raw", nargs="+", metavar="RAW", help="raw captures")
    add_decode_options(p)
    p.add_argument("--depth-range", metavar="NEAR_MM:FAR_MM",
                   help="search only these distances from the sensor (FAR may be inf); default: from infinity to "
                        "3 refocus steps (a) nearer")
    p.add_argument("--min-confidence", type=float, default=None, metavar="C",
                   help="estimates less confident than C (0-1) are written as NaN (default 0.1)")
    p.add_argument("--no-ply", action="store_true", help="do not write the point cloud")
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..camera import Camera
    from ..depth import write_depth_outputs
    from ..depth._confidence import MIN_CONFIDENCE
    from ..depth._search import search_range_a
    from ..errors import LfprocError
    from ..pipeline import load_lightfield, unique_stems

    require_output_folder(args.outdir)
    camera = Camera.from_toml(args.camera)
    depth_range = parse_depth_range(args.depth_range) if args.depth_range is not None else None
    if camera.center_index < 1:
        raise LfprocError(f"{args.camera}: depth needs micro images of 3 px or more (decode.micro_image_px >= 3)")
    search_range_a(camera, depth_range)  # a range the camera cannot focus fails before any decoding
    min_confidence = MIN_CONFIDENCE if args.min_confidence is None else args.min_confidence
    if not 0.0 <= min_confidence <= 1.0:
        raise LfprocError(f"--min-confidence must be in [0, 1], got {min_confidence}")
    setup = setup_from_args(args, camera)  # calibration last: every cheap check fails first
    stems = unique_stems(args.raw)

    def work(path, progress):
        lf = load_lightfield(path, setup)
        write_depth_outputs(args.outdir, stems[path], lf, source=os.path.abspath(path), camera=setup.camera,
                            depth_range_mm=depth_range, point_cloud=not args.no_ply, min_confidence=min_confidence)
        progress.update(1)

    return for_each_capture("depth", args.raw, work)
