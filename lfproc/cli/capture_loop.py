"""Options and the per-capture loop shared by ``decode``, ``refocus`` and ``views``."""

from __future__ import annotations

import sys
import time

from ..errors import LfprocError


def add_decode_options(p, camera_required: bool = True) -> None:
    """The options that say how to decode: camera, grid, white image, resampling, demosaicing.

    ``camera_required=False`` (for commands that take the camera with `camera_from_args`): without
    ``--camera``, Lytro captures bring their camera in their metadata.
    """
    if camera_required:
        p.add_argument("--camera", required=True, metavar="CAM", help="camera TOML file")
    else:
        p.add_argument("--camera", metavar="CAM", help="camera TOML file (optional for Lytro captures: without "
                                                       "it, the camera comes from the first capture's metadata)")
    p.add_argument("--calib", metavar="GRID.json", help="lens grid written by lfproc calibrate")
    p.add_argument("--white", metavar="WHITE", help="white image (also a Lytro .raw with its metadata): "
                                                    "calibrates the grid (without --calib) and corrects vignetting")
    p.add_argument("--white-dir", metavar="DIR", help="Lytro calibration folder: use the white image of the "
                                                      "capture's camera with the nearest zoom and focus steps")
    p.add_argument("--decode-interpolation", default="linear", choices=("nearest", "linear", "cubic", "lanczos"),
                   help="resampling of the sensor into micro images (default linear)")
    p.add_argument("--demosaic", default="fast", choices=("fast", "careful"),
                   help="Bayer demosaicing: fast = bilinear, careful = edge-aware (default fast)")


def captures_of(args) -> list[str]:
    """The capture paths of a command's positional RAW argument(s)."""
    raw = getattr(args, "raw", None)
    return [raw] if isinstance(raw, str) else list(raw or [])


def camera_from_args(args):
    """``--camera``, or for Lytro captures without it the camera in the first capture's metadata."""
    from ..pipeline import camera_for_captures

    return camera_for_captures(args.camera, captures_of(args))


def setup_from_args(args, camera=None):
    """Camera, grid and white image from the parsed options (errors before any capture is read)."""
    from ..pipeline import prepare_decoding

    camera = camera or camera_from_args(args)
    return prepare_decoding(camera, args.calib, args.white, interpolation=args.decode_interpolation,
                            demosaic_method=args.demosaic, white_dir=getattr(args, "white_dir", None),
                            captures=captures_of(args))


def require_output_folder(path: str) -> None:
    """Fail before any work when OUTDIR exists but is not a folder (creating it is left to the writers)."""
    import os

    if os.path.exists(path) and not os.path.isdir(path):
        raise LfprocError(f"{path}: cannot write there (it is a file, not a folder); choose another -o OUTDIR")


def for_each_capture(command: str, paths: list[str], work, total_steps: int | None = None) -> int:
    """Run ``work(path, progress)`` per capture; failures are reported and skipped, the rest complete.

    ``progress`` is a tqdm bar (on stderr, only on a terminal) that ``work`` advances. Returns the exit
    status: 0 if every capture succeeded, 2 if any failed (the summary names them).
    """
    from tqdm import tqdm

    failed, done = [], 0
    start = time.perf_counter()
    with tqdm(total=total_steps or len(paths), unit="img", disable=None, file=sys.stderr,
              desc=f"lfproc {command}") as progress:
        for path in paths:
            try:
                work(path, progress)
                done += 1
            except LfprocError as exc:
                failed.append(path)
                progress.write(f"lfproc {command}: error: {exc}", file=sys.stderr)
    elapsed = time.perf_counter() - start
    summary = f"lfproc {command}: {done} of {len(paths)} captures done in {elapsed:.1f} s"
    if failed:
        summary += f"; failed: {', '.join(failed)}"
    print(summary, file=sys.stderr)
    return 2 if failed else 0
