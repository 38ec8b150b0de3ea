"""Inputs and the per-capture loop shared by ``decode``, ``refocus``, ``views``, ``depth`` and ``viewer``.

An input is a capture to decode (camera raw, TIFF/PNG/EXR, Lytro file) or a light field that
``lfproc decode`` already wrote (``.lfp.npz``), which carries its own camera and grid: commands need no
``--camera``, ``--calib`` or ``--white`` for those.
"""

from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass

from ..errors import LfprocError
from ..lightfield import is_lightfield_file
from .words import command_words


def add_decode_options(p) -> None:
    p.add_argument("--camera", metavar="CAM",
                   help="camera TOML file (not needed for decoded .lfp.npz inputs, which carry theirs, nor for Lytro "
                        "captures, whose metadata gives one with the main lens focused at infinity)")
    p.add_argument("--calib", dest="grid", metavar="GRID.json", help="lens grid written by lfproc calibrate")
    p.add_argument("--white", metavar="WHITE", help="white image (also a Lytro .raw with its metadata): "
                                                    "calibrates the grid (without --calib) and corrects vignetting")
    p.add_argument("--white-dir", metavar="DIR", help="Lytro calibration folder: use the white image of the "
                                                      "capture's camera with the nearest zoom and focus steps")
    add_dark_option(p)
    add_white_is_white_option(p)
    p.add_argument("--decode-interpolation", default="linear", choices=("nearest", "linear", "cubic", "lanczos"),
                   help="resampling of the sensor into micro images (default linear)")
    p.add_argument("--demosaic", default="fast", choices=("fast", "careful"),
                   help="Bayer demosaicing: fast = rim-aware (each channel at its pixel's own ray, the hue of its "
                        "micro image), careful = OpenCV edge-aware (default fast)")


def add_dark_option(p) -> None:
    p.add_argument("--dark", metavar="DARK",
                   help="dark frame (same camera, size and mode; lens cap on): subtracted per pixel from every capture "
                        "and white image after the same level mapping; recorded in grids made with it, and a "
                        "different one later is refused")


def add_white_is_white_option(p) -> None:
    p.add_argument("--white-is-white", action="store_true",
                   help="the white image is a white image: skip the check that refuses (texture ratio above 0.04) or "
                        "warns about (lens-to-lens contrast) a capture of a scene given as one")


def add_output_folder_option(p) -> None:
    p.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                   help="folder for the outputs (created if missing); every image gets a NAME.json sidecar")


@dataclass(frozen=True)
class Inputs:
    """What a command needs to turn each input into a light field.

    ``camera`` is the camera that plans slices before the first capture is read: ``--camera`` when
    given, else the one the first decoded light field carries. ``setup`` (a
    :class:`lfproc.api.DecodeSetup`) is ``None`` when every input is already decoded.
    """

    paths: tuple
    camera: object
    setup: object = None

    def camera_of(self, path: str):
        """The camera that applies to one input (a decoded light field's own, else the decode setup's)."""
        if is_lightfield_file(path):
            from ..lightfield import LightField
            return LightField.read_camera(path) or self.camera
        return self.setup.camera

    def load(self, path: str):
        """The light field of one input: read it if decoded, else decode the capture (its provenance hash is
        computed meanwhile, for the outputs to find ready)."""
        from ..provenance import sha256_soon

        sha256_soon(path)
        if is_lightfield_file(path):
            from ..lightfield import LightField
            lf = LightField.load(path)
            if lf.camera is None:
                raise LfprocError(f"{path}: this light field carries no camera; decode it again with "
                                  f"'lfproc decode --camera CAM'")
            return lf
        return self.setup.decode(path)


def input_camera(args, paths):
    """The camera that plans slices before any capture is read (cheap checks only): ``--camera`` when given,
    else the one the first decoded light field carries."""
    from ..camera import Camera
    from ..lightfield import LightField

    for path in paths:
        if os.path.isdir(path):
            raise LfprocError(f"{path}: is a folder, not a capture file; pass the captures in it (e.g. "
                              f"{os.path.join(path, '*.tif')}), or run 'lfproc batch' on the folder")
        if not os.path.isfile(path):
            raise LfprocError(f"{path}: no such file; check the path")
    to_decode = [p for p in paths if not is_lightfield_file(p)]
    if args.camera:
        return Camera.from_toml(args.camera)
    if to_decode:
        from .lytro_defaults import camera_for_captures
        return camera_for_captures(None, to_decode)    # Lytro metadata, else the error asking for --camera
    camera = LightField.read_camera(paths[0])
    if camera is None:
        raise LfprocError(f"{paths[0]}: this light field carries no camera; give --camera CAM")
    return camera


def prepare_inputs(args, paths, camera=None) -> Inputs:
    """The inputs ready to load: the grid is calibrated (or read) and the white image read, once, when any
    input needs decoding. Call after every cheap check."""
    paths = tuple(paths)
    camera = camera or input_camera(args, paths)
    to_decode = [p for p in paths if not is_lightfield_file(p)]
    setup = setup_from_args(args, camera, to_decode) if to_decode else None
    if setup is not None:   # the camera, grid, white image and dark frame every output's provenance names
        from ..provenance import sha256_soon
        for input_path in setup.inputs.values():
            sha256_soon(input_path)
    return Inputs(paths, camera, setup)


def captures_of(args) -> list[str]:
    """The capture paths of a command's positional RAW argument(s)."""
    raw = getattr(args, "capture", None)
    return [raw] if isinstance(raw, str) else list(raw or [])


def camera_from_args(args):
    """``--camera``, or for Lytro captures without it the camera in the first capture's metadata."""
    from .lytro_defaults import camera_for_captures

    return camera_for_captures(args.camera, captures_of(args))


def setup_from_args(args, camera=None, captures=None):
    """Camera, grid and white image from the parsed options (errors before any capture is read).

    ``captures`` (default: the command's RAW arguments) are the inputs to decode: ``--white-dir``
    picks the white image for the first, and a Lytro white image is checked against it.
    """
    from ..api import prepare_decoding

    camera = camera or camera_from_args(args)
    setup = prepare_decoding(camera, args.white, args.grid, getattr(args, "dark", None),
                             white_dir=getattr(args, "white_dir", None),
                             captures=captures_of(args) if captures is None else list(captures),
                             decode_interpolation=args.decode_interpolation, demosaic=args.demosaic, cache=True,
                             white_is_white=getattr(args, "white_is_white", False))
    for note in (setup.white_note, setup.m_hat_note):
        if note:
            print(f"lfproc: {note}", file=sys.stderr)
    return setup


def require_output_folder(path: str, option: str = "-o OUTDIR") -> None:
    """Fail before any work when OUTDIR cannot be written: a file, a read-only folder, or a missing parent
    that cannot be created. Nothing is created here (the writers create the folder)."""
    path = os.path.abspath(path)
    if os.path.exists(path) and not os.path.isdir(path):
        raise LfprocError(f"{path}: cannot write there (it is a file, not a folder); choose another {option}")
    existing = path
    while not os.path.exists(existing):
        parent = os.path.dirname(existing)
        if parent == existing:
            break
        existing = parent
    if not os.path.isdir(existing) or not _can_create_files_in(existing):
        raise LfprocError(f"{path}: cannot write there ({existing} is not a writable folder); "
                          f"choose another {option}")


def require_output_file(path: str, option: str, example: str) -> None:
    """Fail before any work when the output file ``path`` (``option``, e.g. ``"-o GRID.json"``) cannot be written:
    it is a folder, its folder is a file or not writable, or a missing parent cannot be created
    (:func:`require_output_folder`). ``example``: a file name to suggest inside a folder given by mistake."""
    if os.path.isdir(path):
        flag = option.split()[0]
        raise LfprocError(f"{path}: is a folder; give the file's name, e.g. {flag} {os.path.join(path, example)}")
    require_output_folder(os.path.dirname(os.path.abspath(path)), option)


def _can_create_files_in(folder: str) -> bool:
    """Whether a file can be created in ``folder`` (tried for real: permission bits say nothing to root, nor
    about a read-only file system)."""
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".lfproc-probe-", dir=folder)
    except OSError:
        return False
    os.close(fd)
    os.remove(probe)
    return True


def for_each_capture(command: str, paths: list[str], work, total_steps: int | None = None) -> int:
    """Run ``work(path, progress)`` per capture; failures are reported and skipped, the rest complete.

    ``progress`` is a tqdm bar (on stderr, only on a terminal) that ``work`` advances. With one capture a
    failure is its one error line; with several, a summary line follows (what was done, what failed).
    Returns the exit status: 0 if every capture succeeded, 2 if any failed.
    """
    from tqdm import tqdm

    failed, done = [], 0
    start = time.perf_counter()
    with tqdm(total=total_steps or len(paths), unit="img", disable=None, file=sys.stderr,
              desc=f"lfproc {command}", leave=False) as progress:
        for path in paths:
            try:
                work(path, progress)
                done += 1
            except LfprocError as exc:
                failed.append(path)
                progress.write(f"lfproc {command}: error: {command_words(exc.marked, command)}", file=sys.stderr)
    if len(paths) > 1:
        elapsed = time.perf_counter() - start
        summary = f"lfproc {command}: {done} of {len(paths)} captures done in {elapsed:.1f} s"
        if failed:
            summary += f"; failed: {', '.join(failed)}"
        print(summary, file=sys.stderr)
    return 2 if failed else 0
