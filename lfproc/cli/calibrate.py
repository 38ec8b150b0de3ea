"""``lfproc calibrate``: fit the micro lens grid to a white image and write GRID.json."""

from __future__ import annotations

import os


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="fit the micro lens grid to a white image",
                       description="Find every micro image centre of a white image (a capture of a uniform bright "
                                   "surface), fit the rectangular or hexagonal lens lattice (pitch, rotation, "
                                   "origin) and write it as GRID.json for --calib.")
    p.add_argument("white", metavar="WHITE", help="white image (camera raw, TIFF, PNG, EXR)")
    p.add_argument("--camera", required=True, metavar="CAM",
                   help="camera TOML file: its mla.grid and pitch (mla.pitch_mm / sensor.pixel_pitch_mm) are checked")
    p.add_argument("-o", "--output", required=True, metavar="GRID.json", help="grid file to write")
    p.add_argument("--dark", metavar="DARK", help="dark frame subtracted from the white image first (recorded in "
                                                  "GRID.json, and reused by --calib)")
    from .capture_loop import add_white_is_white_option
    add_white_is_white_option(p)
    p.add_argument("--plot", metavar="FILE.png",
                   help="also draw the fitted centres over the white image (needs matplotlib)")
    p.set_defaults(func=run)


def run(args) -> int:
    import math
    import sys

    from ..atomic import write_text_atomic
    from ..calibrate import exit_pupil_warning, find_grid, implied_exit_pupil
    from ..camera import Camera
    from ..inputs import (ImageFacts, check_same_sensor, check_white_is_white, file_hash, made_from, probe_image,
                          read_dark, subtract_dark)
    from ..io import read_capture
    from .capture_loop import require_output_file, require_output_folder

    camera = Camera.from_toml(args.camera)
    # cheap checks first: where the grid goes, the white image's and the dark frame's headers
    require_output_file(args.output, "-o GRID.json", "grid.json")
    if args.plot:  # fail before any work (and before any output) when matplotlib is missing
        from ..plots import require_matplotlib
        require_matplotlib()
        require_output_folder(os.path.dirname(os.path.abspath(args.plot)), "--plot FILE.png")
    white_facts = probe_image(args.white, camera)
    if args.dark:
        check_same_sensor(probe_image(args.dark, camera), white_facts, "dark frame", "white image")
    dark = read_dark(args.dark, camera) if args.dark else None
    capture = subtract_dark(read_capture(args.white, camera), dark, "white image")
    cfa = capture.cfa if capture.data.ndim == 2 else "none"
    estimate = find_grid(capture.data, kind=camera.grid, approx_pitch_px=camera.pitch_px, cfa=cfa,
                         source=args.white)
    grid = estimate.grid
    check_white_is_white(args.white, capture.data, cfa, grid, white_is_white=args.white_is_white,
                         texture=estimate.texture)
    pupil = implied_exit_pupil(grid.pitch_px, estimate.pitch_sigma_px, camera)
    record = dict(grid.to_json_dict(), white_image=os.path.abspath(args.white),
                  camera=os.path.abspath(args.camera), texture_ratio=estimate.texture,
                  micro_image_scale=pupil.scale, micro_image_scale_sigma=pupil.scale_sigma,
                  # null: the fit cannot tell the scale from 1 (telecentric); the range's null end is infinity
                  implied_exit_pupil_distance_mm=None if math.isinf(pupil.distance_mm) else pupil.distance_mm,
                  implied_exit_pupil_range_mm=[None if math.isinf(v) else v for v in pupil.range_mm],
                  pitch_sigma_px=estimate.pitch_sigma_px,
                  made_from=made_from(camera, ImageFacts.of_capture(capture), file_hash(args.white),
                                      None if dark is None else ImageFacts.of_capture(dark),
                                      None if dark is None else file_hash(args.dark)))
    write_text_atomic(args.output, grid_json_text(record))
    if args.plot:
        plot_grid_fit(capture.data, cfa, estimate, args.plot)
    warnings = list(estimate.warnings)
    warnings.append(exit_pupil_warning(args.white, pupil, camera))
    for line in filter(None, warnings):
        print(f"lfproc calibrate: {line}", file=sys.stderr)
    print(f"{args.output}: {grid.kind} grid of {grid.rows} x {grid.cols} lenses, pitch {grid.pitch_px:.4f} px, "
          f"rotation {grid.rotation_deg:.4f} deg, residual RMS {grid.residual_rms_px:.4f} px "
          f"({int(estimate.inlier.sum())} lenses fitted), {grid.model} lattice, "
          f"micro image scale {pupil.scale:.6f}, exit pupil {pupil.describe()}")
    return 0


def grid_json_text(record: dict) -> str:
    """Strict JSON of a grid record, one top-level key per line.

    Each value is encoded by the json module's C encoder (no indentation inside values): the
    ``centers_xy_px`` list of a 41 Mpx sensor holds some 230,000 pairs, which an indented dump takes
    seconds to write.
    """
    import json

    from ..atomic import json_safe

    items = []
    for key, value in record.items():
        safe = value if key == "centers_xy_px" else json_safe(value)  # centres: finite floats already
        items.append(f"  {json.dumps(str(key))}: {json.dumps(safe, allow_nan=False)}")
    return "{\n" + ",\n".join(items) + "\n}\n"


def plot_grid_fit(white, cfa: str, estimate, path: str, zoom_lenses: int = 6) -> None:
    """The white image with the fitted lens centres (+), fitted (o) and rejected (x) measurements, written atomically.

    Left: the whole image; right: about ``zoom_lenses`` × ``zoom_lenses`` lenses around its centre.
    """
    import numpy as np

    from ..atomic import atomic_path
    from ..calibrate import white_to_mono
    from ..plots import require_matplotlib

    plt = require_matplotlib()
    image = white_to_mono(white, cfa)
    top = float(np.percentile(image, 99.5)) or 1.0
    shown = np.sqrt(np.clip(image / top, 0.0, 1.0))  # a gamma for the eye only
    grid = estimate.grid
    fitted = grid.centers_xy_px().reshape(-1, 2)
    measured, inlier = estimate.centers_xy_px, estimate.inlier
    h, w = image.shape
    half = 0.5 * zoom_lenses * grid.pitch_px
    cx, cy = 0.5 * (w - 1), 0.5 * (h - 1)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5), dpi=110)
    for ax, zoomed in zip(axes, (False, True)):
        ax.imshow(shown, cmap="gray", vmin=0.0, vmax=1.0, interpolation="nearest")
        size = 40 if zoomed else 6
        ax.scatter(fitted[:, 0], fitted[:, 1], marker="+", s=size, c="tab:red", linewidths=0.8, label="fitted lattice")
        ax.scatter(measured[inlier, 0], measured[inlier, 1], marker="o", s=size, facecolors="none",
                   edgecolors="tab:cyan", linewidths=0.6, label="measured, used")
        ax.scatter(measured[~inlier, 0], measured[~inlier, 1], marker="x", s=size, c="tab:orange", linewidths=0.8,
                   label="measured, rejected")
        if zoomed:
            ax.set_xlim(cx - half, cx + half)
            ax.set_ylim(cy + half, cy - half)
            ax.set_title("centre of the image")
        else:
            ax.set_xlim(-0.5, w - 0.5)
            ax.set_ylim(h - 0.5, -0.5)
            ax.set_title(f"{grid.kind}, pitch {grid.pitch_px:.4f} px, rotation {grid.rotation_deg:.4f} deg, "
                         f"RMS {grid.residual_rms_px:.4f} px", fontsize=9)
    axes[1].legend(loc="upper right", fontsize=7, framealpha=0.8)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
