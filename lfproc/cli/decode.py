"""``lfproc decode``: one capture into a light field file (``.lfp.npz``, see lfproc.lightfield)."""

from __future__ import annotations

from .capture_loop import add_decode_options, require_output_file, setup_from_args


def register(sub) -> None:
    p = sub.add_parser("decode", help="decode a raw capture into a light field file",
                       description="Resample a capture along the fitted lens grid into m x m views and save them "
                                   "with the camera and grid (an uncompressed numpy .npz: numpy.load(path)['views'] reads it).")
    p.add_argument("capture", metavar="RAW", help="raw capture (camera raw, TIFF, PNG, EXR, Lytro)")
    add_decode_options(p)
    p.add_argument("-o", "--output", required=True, metavar="LF_FILE", help="output light field file (.lfp.npz)")
    p.set_defaults(func=run)


def run(args) -> int:
    require_output_file(args.output, "-o LF_FILE", "capture.lfp.npz")
    lf = setup_from_args(args).decode(args.capture)
    lf.save(args.output)
    m, _, ny, nx, ch = lf.views.shape
    lit = int((lf.views != 0).any(axis=(2, 3, 4)).sum())
    print(f"{args.output}: {m}x{m} views ({lit} carry light) of {ny}x{nx} lenses, {ch} channel(s)")
    return 0
