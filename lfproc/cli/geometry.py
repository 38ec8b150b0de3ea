"""``lfproc geometry``: slice distances and DOF, and the virtual cameras, of a camera file."""

from __future__ import annotations

import math
import sys

from .common import dumps_strict, parse_number_list


def register(sub) -> None:
    p = sub.add_parser("geometry", help="distance and DOF of refocused slices, position and tilt of views",
                       description="Print the paraxial geometry (paper Eqs. 13-34) of a camera: for every "
                                   "refocus parameter a its distance and depth of field from the sensor, and "
                                   "for every view its virtual camera position, tilt and the baseline.")
    p.add_argument("--camera", required=True, metavar="CAM", help="camera TOML file")
    p.add_argument("--a", default="0:5", metavar="LIST",
                   help="refocus parameters: numbers and inclusive ranges START:STOP[:STEP] (default 0:5)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.add_argument("--plot", metavar="FILE.png", help="also draw each slice's distance and DOF (needs matplotlib)")
    p.add_argument("--wavelength-nm", type=float, default=550.0, help="wavelength for the Airy limit (default 550)")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import geometry
    from ..camera import Camera
    from ..errors import LfprocError

    camera = Camera.from_toml(args.camera)
    a_values = parse_number_list(args.a, "--a")
    if not (args.wavelength_nm > 0 and math.isfinite(args.wavelength_nm)):
        raise LfprocError(f"--wavelength-nm must be a positive number, got {args.wavelength_nm}")
    slices = geometry.slice_geometry(camera, a_values)
    views = geometry.view_geometry(camera)
    if args.plot:
        from ..plots import plot_slices
        plot_slices(camera, slices, args.plot)
    if args.json:
        print(dumps_strict({"slices": slices.records(), "views": views.records(),
                            "baseline_mm": views.baseline_mm}))
        return 0
    check = geometry.diffraction_check(camera, args.wavelength_nm * 1e-6, warn=False)
    gaps = geometry.integer_slice_gaps(camera, [a for a in a_values if float(a).is_integer()])
    sys.stdout.write(format_table(camera, slices, views, gaps, check, args.camera))
    return 0


def _mm(value: float, width: int = 11) -> str:
    return f"{'inf':>{width}}" if math.isinf(value) else f"{value:>{width}.3f}"


def format_table(camera, slices, views, gaps, check, path) -> str:
    """A readable table in the layout of the paper's Tables 2 and 4."""
    out = [f"camera {camera.name or path}: m = {camera.m_hat} px per micro image, effective pixel pitch "
           f"{camera.effective_pixel_pitch_mm * 1e3:.3f} um, b_U - f_U = "
           f"{camera.image_distance_mm - camera.main_focal_length_mm:.4f} mm",
           "distances from the sensor [mm]",
           f"{'a':>8} {'near d_a-':>11} {'d_a':>11} {'far d_a+':>11} {'DOF D_a':>11}"]
    for r in slices.records():
        out.append(f"{r['a']:>8g} {_mm(r['near_mm'])} {_mm(r['distance_mm'])} {_mm(r['far_mm'])} {_mm(r['dof_mm'])}")
    for a, lo, hi in gaps:
        out.append(f"  gap between a = {a:g} and {a + 1:g}: {lo:.3f} .. {hi:.3f} mm is in no integer slice's DOF")
    out.append("")
    out.append(f"views (Eqs. 17, 33): baseline of adjacent views {views.baseline_mm:.4f} mm")
    out.append(f"{'i':>5} {'position F_i [mm]':>18} {'tilt [deg]':>11}")
    for r in views.records():
        out.append(f"{r['i']:>5d} {r['position_mm']:>18.4f} {r['tilt_deg']:>11.4f}")
    out.append("")
    out.append(check.message())
    return "\n".join(out) + "\n"
