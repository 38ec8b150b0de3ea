"""``lfproc camera``: a contract camera file from a Lytro capture's metadata, with where each number came from."""

from __future__ import annotations

import sys


def register(sub) -> None:
    p = sub.add_parser("camera", help="write a camera file from a Lytro file's or napari-LF's metadata",
                       description="Read the metadata of a Lytro capture or white image (.lfr/.lfp, or NAME.raw "
                                   "with NAME.txt/.json) and write a camera file: pixel and lens pitch, hexagonal "
                                   "tiling, micro lens focal length (MLA-to-sensor distance), main lens focal "
                                   "length and f-number at the capture's zoom, exit pupil distance, levels, CFA. "
                                   "What the metadata lacks (the focus distance, principal planes) comes from "
                                   "--focus-distance or a default; the [provenance] table says which. napari-LF's "
                                   "metadata.txt gives a light-field microscope's camera file (ulens_focal_distance as f_s, pixel_size at the lenslets). For a "
                                   "processed Lytro picture without camera metadata (a first-generation stack), "
                                   "write the camera file from another file of that camera and give it to "
                                   "'lfproc export PICTURE --camera CAM.toml [--focus-distance MM]'.")
    p.add_argument("file", metavar="FILE", help="Lytro capture, white image or processed picture (Illum .LFP, first "
                                                "generation -stk.lfp with its frame metadata), or napari-LF's "
                                                "metadata.txt")
    p.add_argument("-o", "--output", required=True, metavar="CAMERA.toml", help="camera file to write")
    p.add_argument("--focus-distance", dest="focus_distance_mm", type=float, metavar="MM",
                   help="distance from the sensor the main lens was focused at, in mm (inf allowed); "
                        "default: infinity (b_U = f_U)")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..atomic import write_text_atomic
    from ..errors import LfprocError
    from ..io import is_lytro_file, lytro_camera
    from ..io import existing_file
    from ..io import camera_metadata
    from .capture_loop import require_output_file

    require_output_file(args.output, "-o CAMERA.toml", "camera.toml")   # before any input is read
    path = existing_file(args.file)
    from ..io import is_napari_metadata

    if not is_lytro_file(path) and is_napari_metadata(path):
        return _napari(path, args)
    if not is_lytro_file(path):
        raise LfprocError(f"{path}: not a Lytro file (.lfr/.lfp, or .raw with .txt/.json metadata) nor napari-LF "
                          f"metadata (metadata.txt); write other camera files by hand (README)")
    meta = camera_metadata(path)
    built = lytro_camera(meta, args.focus_distance_mm)
    try:
        write_text_atomic(args.output, _lambda_note(meta) + built.to_toml())
    except OSError as exc:
        raise LfprocError(f"{args.output}: cannot write ({exc.strerror or exc}); check the folder") from None
    cam = built.camera
    defaults = [key for key, text in built.provenance if text.startswith("default")]
    print(f"{args.output}: Lytro camera, {cam.pitch_px:.3f} px {cam.grid} lenses ({_m_hat_words(cam)}), f_s "
          f"{cam.mla_focal_length_mm:.4f} mm, {cam.main_optics.describe()}; defaults (see [provenance]): "
          f"{', '.join(defaults)}", file=sys.stdout)
    return 0


def _lambda_note(meta) -> str:
    """A comment with the focus distance the lambda reading gives (docs/lytro.md), when the metadata allows it."""
    from ..errors import LfprocError
    from ..geometry import slice_distance_mm
    from ..io import lambda_map

    try:
        focus = slice_distance_mm(lambda_map(meta).camera, 0.0)
    except LfprocError:
        return ""
    return (f"# lambda reading (docs/lytro.md, not a published specification): this capture's infinityLambda "
            f"{meta.infinity_lambda:g} puts its focus {focus:.1f} mm from the sensor; the camera below is focused at "
            f"infinity unless --focus-distance says otherwise\n"
            f"# the focus is this capture's only: a camera file for it is 'lfproc camera FILE --focus-distance "
            f"{focus:.1f}'; other pictures of this camera focused elsewhere (their own metadata says where)\n")


def _napari(path: str, args) -> int:
    """A microscope camera file from napari-LF's metadata.txt (mapping: docs/microscope.md)."""
    from ..atomic import write_text_atomic
    from ..errors import LfprocError
    from ..io import napari_camera

    if args.focus_distance_mm is not None:
        raise LfprocError(f"{path}: --focus-distance is for a camera's main lens; a microscope has none (its slices "
                          f"are placed by z, lfproc refocus --z-range)")
    camera, notes = napari_camera(path)
    try:
        write_text_atomic(args.output, "".join(f"# {note}\n" for note in notes) + camera.to_toml())
    except OSError as exc:
        raise LfprocError(f"{args.output}: cannot write ({exc.strerror or exc}); check the folder") from None
    print(f"{args.output}: light-field microscope, {camera.main_optics.describe()}, {camera.pitch_px:.3f} px "
          f"rectangular lenses ({_m_hat_words(camera)}), f_s "
          f"{camera.mla_focal_length_mm:g} mm; every number's source in [provenance]", file=sys.stdout)
    return 0


def _m_hat_words(camera) -> str:
    """How m̂ will be chosen: the camera file leaves it to the white image's measured micro image pitch."""
    return f"m̂ from the white image's measured pitch; {camera.m_hat} from this nominal one"
