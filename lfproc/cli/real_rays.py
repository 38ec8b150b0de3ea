"""``lfproc geometry --real-rays``: the real-ray records beside the paraxial ones (JSON and a text table).

The numbers come from :func:`lfproc.geometry.real_ray_slices` and :func:`lfproc.geometry.real_ray_views`;
this module only attaches them to the report and prints them (docs/real-lens.md).
"""

from __future__ import annotations

import math


def real_ray_records(camera, a_values, view_extent, view_offsets):
    """(slice records, view records) of the real rays, ``None`` for null."""
    from .. import geometry
    slices = geometry.real_ray_slices(camera, a_values, view_extent).records()
    views = geometry.real_ray_views(camera, view_offsets).records()
    return slices, views


def add_real_rays(report: dict, camera, view_extent) -> dict:
    """Each slice and view of a ``geometry --json`` report gains ``"real_rays"``; ``"prescription"`` is added."""
    slices, views = real_ray_records(camera, [r["a"] for r in report["slices"]], view_extent,
                                     [r["i"] for r in report["views"]])
    report["slices"] = [dict(record, real_rays=real) for record, real in zip(report["slices"], slices)]
    report["views"] = [dict(record, real_rays=real) for record, real in zip(report["views"], views)]
    from .. import geometry
    report["prescription"] = geometry.real_ray_lens(camera)
    return report


def _deviation(paraxial: float, real) -> float | None:
    """The paper's Eq. 37: (paraxial − real)/paraxial × 100; ``None`` where either is missing or infinite."""
    if real is None or not math.isfinite(paraxial) or paraxial == 0.0:
        return None
    return (paraxial - real) / paraxial * 100.0


def _cell(value, width: int, digits: int = 3) -> str:
    if value is None:
        return f"{'-':>{width}}"
    return f"{'inf':>{width}}" if math.isinf(value) else f"{value:>{width}.{digits}f}"


def format_real_rays(camera, slices, views, view_extent) -> str:
    """Paraxial and real side by side with the deviation (Eq. 37), as the paper's Tables 2 and 4."""
    real_slices, real_views = real_ray_records(camera, [r["a"] for r in slices.records()],
                                               view_extent, [r["i"] for r in views.records()])
    from .. import geometry
    lens = geometry.real_ray_lens(camera)
    pupil = ("at infinity" if math.isinf(lens["exit_pupil_distance_mm"])
             else f"{lens['exit_pupil_distance_mm']:.3f} mm from the MLA")
    out = ["", f"real rays through {lens['surfaces']} surfaces of {lens['source']} at {lens['wavelength_nm']:g} nm: "
               f"f_U = {lens['focal_length_mm']:.4f} mm, H1U-H2U = {lens['principal_plane_gap_mm']:.4f} mm, "
               f"exit pupil {pupil}",
           "distances from the sensor [mm]: paraxial | real rays | deviation (paraxial - real)/paraxial [%]",
           f"{'a':>8} {'d_a-':>10} {'d_a':>10} {'d_a+':>10} | {'d_a-':>10} {'d_a':>10} {'d_a+':>10} {'spread':>10} |"
           f" {'ERR_a-':>8} {'ERR_a':>8} {'ERR_a+':>8}"]
    outside = False
    for p, r in zip(slices.records(), real_slices):
        errs = [_deviation(p[k], r[k]) for k in ("near_mm", "distance_mm", "far_mm")]
        lo, hi = r["near_mm"], r["far_mm"]
        mark = ""
        if lo is not None and math.isfinite(p["distance_mm"]) and (
                p["distance_mm"] < lo or (hi is not None and p["distance_mm"] > hi)):
            mark, outside = " *", True
        out.append(f"{p['a']:>8g} {_cell(p['near_mm'], 10)} {_cell(p['distance_mm'], 10)} {_cell(p['far_mm'], 10)} | "
                   f"{_cell(r['near_mm'], 10)} {_cell(r['distance_mm'], 10)} {_cell(r['far_mm'], 10)} "
                   f"{_cell(r['spread_mm'], 10)} | {_cell(errs[0], 8)} {_cell(errs[1], 8)} {_cell(errs[2], 8)}{mark}")
    out.append("  - : the rays do not cross in front of the lens (or the paraxial value lies inside or behind it)")
    if outside:
        out.append("  * : the paraxial d_a lies outside the real-ray DOF [d_a-, d_a+]")
    out += ["", "views: paraxial | real rays (least-squares convergence of each view's chief rays)",
            f"{'i':>5} {'F_i [mm]':>10} {'tilt [deg]':>11} | {'F_i [mm]':>10} {'tilt [deg]':>11} {'distance':>10}"]
    for p, r in zip(views.records(), real_views):
        out.append(f"{p['i']:>5d} {p['position_mm']:>10.4f} {p['tilt_deg']:>11.4f} | "
                   f"{_cell(r['position_mm'], 10, 4)} {_cell(r['tilt_deg'], 11, 4)} {_cell(r['distance_mm'], 10)}")
    return "\n".join(out) + "\n"
