"""``lfproc depth``: metric depth maps (mm), their confidence and an all-in-focus image of captures."""

from __future__ import annotations

import math

from .capture_loop import (
    add_decode_options,
    add_output_folder_option,
    for_each_capture,
    input_camera,
    prepare_inputs,
    require_output_folder,
)
from .common import add_aperture_option, aperture_extent, parse_depth_range


def register(sub) -> None:
    p = sub.add_parser("depth", help="depth map in mm, confidence and all-in-focus image of each capture",
                       description="Decode each capture and estimate the distance from the sensor of the surface "
                                   "seen at every lens (a sweep over the refocus parameter a, mapped to mm by the "
                                   "paper's geometry). Writes STEM_depth.tif (float32 mm, NaN = unknown), "
                                   "STEM_depth_confidence.tif, STEM_allfocus.tif, STEM_depth_preview.png and "
                                   "STEM_depth_points.ply, each with a sidecar; the same metadata embedded.")
    p.add_argument("capture", nargs="+", metavar="RAW",
                   help="captures (camera raw, TIFF/PNG/EXR, Lytro) or light fields from lfproc decode (.lfp.npz)")
    add_decode_options(p)
    p.add_argument("--depth-range", dest="depth_range_mm", metavar="NEAR_MM:FAR_MM",
                   help="search only these distances from the sensor (FAR may be inf); default: from infinity to "
                        "a = 3 nearer, narrowed to what the scene occupies")
    p.add_argument("--z-range", dest="z_range_um", metavar="Z0:Z1[:STEP]",
                   help="microscope cameras: search only these depths, micrometres from the native object plane "
                        "(positive towards the objective), with STEP the sweep step in um; default: the N_u "
                        "resolvable depths, |a| <= 1")
    p.add_argument("--min-confidence", type=float, default=None, metavar="C",
                   help="estimates less confident than C (0-1) are written as NaN (default 0.1)")
    p.add_argument("--no-ply", action="store_true", help="do not write the point cloud")
    add_output_folder_option(p)
    add_aperture_option(p)
    p.set_defaults(func=run)


def check_depth_options(args, camera):
    """The depth range and confidence threshold, checked against ``camera`` before any capture is read."""
    from ..depth import MIN_CONFIDENCE, search_range_a
    from ..errors import LfprocError

    depth_range = parse_depth_range(args.depth_range_mm) if args.depth_range_mm is not None else None
    if args.z_range_um is not None and depth_range is not None:
        raise LfprocError("give --depth-range (mm, cameras) or --z-range (um, microscopes), not both")
    if camera.center_index < 1:
        raise LfprocError(f"{camera.source or 'camera'}: depth needs micro images of 3 px or more "
                          f"(decode.micro_image_px >= 3)")
    if args.z_range_um is None:
        search_range_a(camera, depth_range)   # a range this camera cannot focus fails here
    min_confidence = MIN_CONFIDENCE if args.min_confidence is None else args.min_confidence
    if not 0.0 <= min_confidence <= 1.0:
        raise LfprocError(f"--min-confidence must be in [0, 1], got {min_confidence}")
    return depth_range, min_confidence, z_sweep(args, camera)


def z_sweep(args, camera) -> dict:
    """``--z-range Z0:Z1[:STEP]`` as the depth sweep's ``a_range`` (and ``step``), checked against ``camera``."""
    from .. import geometry
    from ..camera import NATIVE_PLANE_UM
    from ..errors import LfprocError
    if args.z_range_um is None:
        return {}
    geometry.require_space(camera, NATIVE_PLANE_UM, "--z-range (use --depth-range NEAR_MM:FAR_MM for a camera)")
    try:
        values = [float(v) for v in args.z_range_um.split(":")]
    except ValueError:
        values = []
    if len(values) not in (2, 3) or not all(math.isfinite(v) for v in values) or values[0] == values[1] or (
            len(values) == 3 and values[2] <= 0):
        raise LfprocError(f"--z-range: {args.z_range_um!r} must be Z0:Z1 or Z0:Z1:STEP in micrometres with Z0 != Z1 "
                          f"and STEP > 0, e.g. -50:50 or -50:50:2")
    ends = [float(a) for a in geometry.position_parameter(camera, values[:2])]
    out = {"a_range": (min(ends), max(ends))}
    if len(values) == 3:   # a step in z as one in a: z is linear in a through the native object plane
        out["step"] = float(geometry.position_parameter(camera, values[2])) - \
            float(geometry.position_parameter(camera, 0.0))
    return out


def run(args) -> int:
    from ..api import depth_map
    from ..outputs import unique_stems
    from ..viewpoints import with_aperture

    require_output_folder(args.outdir)
    stems = unique_stems(args.capture)
    camera = input_camera(args, args.capture)
    depth_range, min_confidence, sweep = check_depth_options(args, camera)
    aperture_extent(camera, args.aperture)            # an impossible --aperture fails before any work
    inputs = prepare_inputs(args, args.capture, camera)   # calibration last: every cheap check fails first

    def work(path, progress):
        lf = with_aperture(inputs.load(path), args.aperture)
        sweep = check_depth_options(args, lf.camera)[2]
        result = depth_map(lf, depth_range_mm=depth_range, min_confidence=min_confidence, **sweep)
        result.save(args.outdir, stems[path], point_cloud=not args.no_ply)
        progress.update(1)
        print(f"{path}: {result.summary()} -> {args.outdir}/{stems[path]}_depth*.*, {stems[path]}_allfocus.tif")

    return for_each_capture("depth", args.capture, work)
