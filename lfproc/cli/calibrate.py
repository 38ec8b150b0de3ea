"""``lfproc calibrate``: fit the micro lens grid to a white image (:func:`lfproc.calibrate_white`) and write
GRID.json (``LensGrid.save``)."""

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
    from ..api import calibrate_white
    from ..calibrate import implied_exit_pupil
    from ..camera import Camera
    from .capture_loop import require_output_file, require_output_folder

    camera = Camera.from_toml(args.camera)
    # cheap checks first: where the grid goes (the white image's and the dark frame's headers: calibrate_white)
    require_output_file(args.output, "-o GRID.json", "grid.json")
    if args.plot:  # fail before any work (and before any output) when matplotlib is missing
        from ..plots import require_matplotlib
        require_matplotlib()
        require_output_folder(os.path.dirname(os.path.abspath(args.plot)), "--plot FILE.png")
    grid = calibrate_white(args.white, camera, dark=args.dark, white_is_white=args.white_is_white)
    grid.save(args.output)
    fit = grid.calibration
    if args.plot:
        plot_grid_fit(_white_image(args, camera), grid, args.plot)
    pupil = implied_exit_pupil(grid.pitch_px, fit.pitch_sigma_px, camera)
    print(f"{args.output}: {grid.kind} grid of {grid.rows} x {grid.cols} lenses, pitch {grid.pitch_px:.4f} px, "
          f"rotation {grid.rotation_deg:.4f} deg, residual RMS {grid.residual_rms_px:.4f} px "
          f"({int(fit.inlier.sum())} lenses fitted), {grid.model} lattice, "
          f"micro image scale {fit.micro_image_scale:.6f}, exit pupil {pupil.describe()}")
    return 0


def _white_image(args, camera):
    """The white image as the fit saw it (dark frame subtracted), read again for the plot."""
    from ..inputs import subtract_dark
    from ..io import read_capture

    dark = read_capture(args.dark, camera) if args.dark else None
    return subtract_dark(read_capture(args.white, camera), dark, "white image")


def plot_grid_fit(white, grid, path: str, zoom_lenses: int = 6) -> None:
    """The white image (a `Capture`) with the lens centres of ``grid`` (+) and the centres its fit measured, used
    (o) and rejected (x) (``grid.calibration``), written atomically.

    Left: the whole image; right: about ``zoom_lenses`` × ``zoom_lenses`` lenses around its centre.
    """
    import numpy as np

    from ..atomic import atomic_path
    from ..calibrate import white_to_mono
    from ..plots import require_matplotlib

    plt = require_matplotlib()
    image = white_to_mono(white.data, white.cfa if white.data.ndim == 2 else "none")
    top = float(np.percentile(image, 99.5)) or 1.0
    shown = np.sqrt(np.clip(image / top, 0.0, 1.0))  # a gamma for the eye only
    fitted = grid.centers_xy_px().reshape(-1, 2)
    measured, inlier = grid.calibration.measured_centers_xy_px, grid.calibration.inlier
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
