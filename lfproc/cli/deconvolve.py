"""``lfproc deconvolve``: a light-field microscope capture to a volume in micrometres (wave-optics Richardson–Lucy)."""

from __future__ import annotations

import math
import os
import sys

from ..api import DEFAULT_SUPERRES
from .capture_loop import add_decode_options, add_output_folder_option, input_camera, prepare_inputs, require_output_folder


def register(sub) -> None:
    p = sub.add_parser("deconvolve", help="3-D deconvolution of a light-field microscope capture into a volume (um)",
                       description="Decode a light-field microscope capture and deconvolve it into a volume with a "
                                   "wave-optics model of the microscope (Richardson-Lucy with the depth-adaptive "
                                   "anti-aliasing filter). Writes OUTDIR/STEM_volume.ome.tif (an OME-TIFF z-stack, "
                                   "ZYX, with its voxel size in um: Fiji and napari open it at scale) and "
                                   "OUTDIR/STEM_volume.json (z_um per plane, voxel_um, iterations, superres, the "
                                   "optics, provenance). The operators are kept in lfproc's cache (lfproc info "
                                   "--cache): later captures of the same rig and z range reuse them.")
    p.add_argument("capture", metavar="CAPTURE", help="the capture (or a light field from lfproc decode, .lfp.npz)")
    add_decode_options(p)
    p.add_argument("--z-range", dest="z_um", required=True, metavar="Z0:Z1:STEP",
                   help="the planes, micrometres from the native object plane (positive towards the objective), "
                        "from Z0 to Z1 in steps of STEP, e.g. -100:100:20")
    add_deconvolution_options(p)
    p.add_argument("--stem", metavar="STEM", help="output file names' start (default: the capture's name)")
    add_output_folder_option(p)
    p.set_defaults(func=run)


def add_deconvolution_options(p) -> None:
    """The options of the deconvolution itself, the same in ``lfproc deconvolve`` and ``lfproc batch --deconvolve``."""
    p.add_argument("--iterations", type=int, default=8, metavar="N", help="Richardson-Lucy iterations (default 8)")
    p.add_argument("--superres", type=int, default=DEFAULT_SUPERRES, metavar="S",
                   help="voxels per lenslet pitch along x and y (1 to the samples per lens; default 3)")
    p.add_argument("--background", default="auto", metavar="B",
                   help="background per sample, the white image's level being 1 (default auto: the 1st percentile)")
    p.add_argument("--tolerance", type=float, default=None, metavar="T",
                   help="stop early once an iteration lowers the misfit by less than this fraction")
    p.add_argument("--no-filter", action="store_true", help="skip the depth-adaptive anti-aliasing filter")


def deconvolution_settings(args, camera, z_range: str) -> dict:
    """The keyword arguments of :func:`lfproc.deconvolve` the options ask for (``z_um`` from ``z_range``, the text
    of ``--z-range``), checked against the camera before any work: a camera without microscope optics, S beyond
    m̂, planes out of reach."""
    from ..errors import LfprocError
    from ..wave import check_superres, check_z, wave_optics_of

    z = z_planes(z_range)
    if args.iterations < 1:
        raise LfprocError(f"--iterations must be 1 or more, got {args.iterations}")
    optics = wave_optics_of(camera, camera.source or args.camera or "camera")
    check_superres(args.superres, camera.m_hat)
    check_z(z, optics, camera.mla_pitch_mm * 1000.0)       # the light field's own extent is checked once decoded
    background = args.background if args.background == "auto" else _number(args.background)
    return {"z_um": z, "iterations": args.iterations, "superres": args.superres, "background": background,
            "tolerance": args.tolerance, "antialias": not args.no_filter}


def z_planes(text: str) -> list[float]:
    """``Z0:Z1:STEP`` → the planes Z0, Z0 ± STEP, … up to Z1 (inclusive within a millionth of a step)."""
    from ..errors import LfprocError

    try:
        values = [float(v) for v in text.split(":")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values) or values[2] <= 0:
        raise LfprocError(f"--z-range: {text!r} must be Z0:Z1:STEP in micrometres with STEP > 0, e.g. -100:100:20")
    z0, z1, step = values
    count = int(math.floor(abs(z1 - z0) / step + 1e-6)) + 1
    if count > 1000:
        raise LfprocError(f"--z-range {text} asks for {count} planes; use a larger STEP")
    sign = 1.0 if z1 >= z0 else -1.0
    return [z0 + sign * i * step for i in range(count)]


def run(args) -> int:
    from tqdm import tqdm

    from ..api import deconvolve
    from ..atomic import all_or_nothing
    from ..outputs import output_stem

    require_output_folder(args.outdir)
    camera = input_camera(args, [args.capture])
    settings = deconvolution_settings(args, camera, args.z_um)          # refused before any work
    stem = args.stem or output_stem(args.capture)
    inputs = prepare_inputs(args, [args.capture], camera)          # calibration last: every cheap check fails first
    lf = inputs.load(args.capture)
    with tqdm(total=len(settings["z_um"]) + args.iterations, unit="step", disable=None, file=sys.stderr,
              desc="lfproc deconvolve", leave=False) as bar:
        def progress(stage, done, total):
            bar.set_postfix_str(stage)
            bar.update(1)

        volume = deconvolve(lf, **settings, cache=True, progress=progress)
    with all_or_nothing():                                   # both files or neither, even when interrupted
        stack, sidecar = volume.save(args.outdir, stem)
    print(f"{args.capture}: {volume!r} -> {os.path.join(args.outdir, os.path.basename(stack))}, "
          f"{os.path.basename(sidecar)}")
    return 0


def _number(text: str) -> float:
    from ..errors import LfprocError

    try:
        return float(text)
    except ValueError:
        raise LfprocError(f"--background must be auto or a number, got {text!r}") from None
