"""Figures and tables of docs/real-lens.md: the paper's Table 2 experiment repeated on a real Double Gauss.

Run from the repository root::

    PYTHONPATH=$PWD python scripts/real_lens_figure.py          # prints the tables (Markdown)

writes ``docs/real-lens.png`` (deviation against distance; distances with and without the lens's own
exit pupil) and ``docs/real-lens-bundle.png`` (the summed bundle of slice a = 1 through the real lens).
Needs matplotlib. Nothing here is random; a rerun gives the same numbers.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from lfproc import geometry as g
from lfproc.camera import Camera
from lfproc.geometry._real_rays import _frame, slice_rays, trace_to_object_space

ROOT = Path(__file__).resolve().parent.parent
CAMS = ROOT / "lfproc" / "samples" / "cameras"
DOCS = ROOT / "docs"


def camera(kind: str, extra_mm: float = 0.0, f_s: float = 2.749) -> Camera:
    """The sample Double Gauss camera: ``kind`` "telecentric" (stop at F1U) or "own" (its own stop)."""
    name = "double-gauss-f100-telecentric.toml" if kind == "telecentric" else "double-gauss-f100.toml"
    cam = Camera.from_toml(CAMS / name)
    if f_s != cam.mla_focal_length_mm:
        old = f"focal_length_mm = {cam.mla_focal_length_mm!r}\n"
        text = cam.to_toml().replace(old, f"focal_length_mm = {f_s!r}\n", 1)     # the [mla] one
        cam = Camera.from_toml_string(text, cam.source)
    return cam.with_optics(cam.main_optics.with_prescription(cam.main_optics.prescription, cam.main_optics.focal_length_mm + extra_mm))


def _fmt(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return "∞" if math.isinf(x) else f"{x:.3f}"


def table(cam: Camera, a_values) -> str:
    """Markdown rows as the paper's Table 2: prediction, real rays, deviation (Eq. 37)."""
    para = g.slice_geometry(cam, np.asarray(a_values, dtype=float))
    real = g.real_ray_slices(cam, a_values)
    rows = ["| a | d_a− | d_a | d_a+ | real d_a− | real d_a | real d_a+ | spread "
            "| ERR_a− % | ERR_a % | ERR_a+ % |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for k, a in enumerate(a_values):
        p = [para.near_mm[k], para.distance_mm[k], para.far_mm[k]]
        r = [real.near_mm[k], real.distance_mm[k], real.far_mm[k]]
        err = [(pp - rr) / pp * 100 if math.isfinite(pp) and not math.isnan(rr) else None for pp, rr in zip(p, r)]
        rows.append(f"| {a:g} | " + " | ".join(_fmt(x) for x in p + r + [real.spread_mm[k]] + err) + " |")
    return "\n".join(rows)


def views_table(cam: Camera, i_values) -> str:
    real = g.real_ray_views(cam, i_values)
    pos, tilt = g.view_positions_mm(cam, np.asarray(i_values)), g.view_tilts_deg(cam, np.asarray(i_values))
    rows = ["| i | F_i | Φ_i [°] | real F_i | real Φ_i [°] | real distance |",
            "| --- | --- | --- | --- | --- | --- |"]
    for k, i in enumerate(i_values):
        rows.append(f"| {i} | {pos[k]:.4f} | {tilt[k]:.4f} | {real.position_mm[k]:.4f} | {real.tilt_deg[k]:.4f} | "
                    f"{real.distance_mm[k]:.3f} |")
    return "\n".join(rows)


def figure_deviation(path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.6))
    a = np.linspace(0.05, 5, 300)
    colours = {0.0: "tab:blue", 10.0: "tab:orange", 20.0: "tab:green"}
    for extra, colour in colours.items():
        for kind, style in (("telecentric", "-"), ("own", "--")):
            cam = camera(kind, extra)
            para = g.slice_geometry(cam, a)
            real = g.real_ray_slices(cam, a)
            err = (para.distance_mm - real.distance_mm) / para.distance_mm * 100
            label = f"b_U = f_U + {extra:g} mm, " + ("stop at F1U (paper)" if kind == "telecentric" else "own stop")
            ax1.plot(para.distance_mm, err, style, color=colour, label=label)
            near_err = (para.near_mm - real.near_mm) / para.near_mm * 100
            ax1.plot(para.near_mm, near_err, style, color=colour, alpha=0.35, lw=0.8)
            if extra == 0.0:
                ax2.plot(a, para.distance_mm, style, color="k" if kind == "telecentric" else "tab:red",
                         label=("paraxial, " + ("stop at F1U (paper)" if kind == "telecentric" else "own stop")))
                ax2.plot(a, real.distance_mm, ":", color="k" if kind == "telecentric" else "tab:red", lw=2.5,
                         alpha=0.6, label="real rays, " + ("stop at F1U" if kind == "telecentric" else "own stop"))
    ax1.set_xscale("log")
    ticks = [150, 200, 300, 500, 1000, 2000, 3000]
    ax1.set_xticks(ticks, [str(t) for t in ticks])
    ax1.minorticks_off()
    ax1.set_xlabel("paraxial distance from the sensor [mm]")
    ax1.set_ylabel("deviation (paraxial − real)/paraxial [%]")
    ax1.set_title("d_a (thick) and d_a− (thin) of the Double Gauss, f_s = 2.749 mm")
    ax1.axhline(0, color="grey", lw=0.5)
    ax1.legend(fontsize=7)
    ax2.set_yscale("log")
    ax2.set_xlabel("refocus parameter a")
    ax2.set_ylabel("d_a from the sensor [mm]")
    ax2.set_title("b_U = f_U: the exit pupil moves slices, aberrations barely")
    ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def figure_bundle(path: Path, a: float = 1.0) -> None:
    """Object-space rays of slice a's symmetric pairs (views ±v) and its DOF border rays, near the crossing."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cam = camera("telecentric")
    frame = _frame(cam)
    y0, mu = slice_rays(cam, np.array([a]))
    z, y, dz, dy = trace_to_object_space(frame, y0[:, 0], mu[:, 0])
    real = g.real_ray_slices(cam, [a])
    para = g.slice_geometry(cam, a)
    fig, (ax, axz) = plt.subplots(1, 2, figsize=(12, 4.4), gridspec_kw=dict(width_ratios=[1.3, 1]))
    d_lo, d_hi = real.near_mm[0] - 4, real.far_mm[0] + 4
    views = np.arange(1, len(z) - 3 + 1)
    cmap = plt.get_cmap("viridis")
    for k in range(len(z)):
        t = np.linspace(0, 1, 2)
        # the ray and its mirror image from the sensor-side distance d_lo to d_hi
        dist_start, dist_end = d_lo, d_hi
        s0 = ((frame.z_sensor - dist_start) - z[k]) / dz[k]
        s1 = ((frame.z_sensor - dist_end) - z[k]) / dz[k]
        ss = s0 + (s1 - s0) * t
        dd = frame.z_sensor - (z[k] + ss * dz[k])
        yy = y[k] + ss * dy[k]
        if k == 0:
            style = dict(color="k", lw=2.0, label=f"views ±12, pixel centres: d_a (real {real.distance_mm[0]:.3f} mm)")
        elif k in (1, 2):
            style = dict(color="tab:red", lw=1.2, ls="--",
                         label=("pixel and lens borders: d_a−" if k == 1 else "pixel and lens borders: d_a+"))
        else:
            style = dict(color=cmap((views[k - 3] - 1) / 11), lw=0.7, alpha=0.9,
                         label="views ±1 … ±12, pixel centres (spread)" if k == 3 else None)
        for sign in (1, -1):
            for axis in (ax, axz):
                axis.plot(dd, sign * yy * 1e3, **(style if sign == 1 else {**style, "label": None}))
    for axis in (ax, axz):
        axis.axvline(para.distance_mm, color="tab:blue", lw=0.8, ls=":", label="paraxial d_a" if axis is ax else None)
        axis.axhline(0, color="grey", lw=0.5)
        axis.set_xlabel("distance from the sensor [mm]")
    ax.set_ylabel("height [µm]")
    ax.set_ylim(-1500, 1500)
    ax.set_title(f"slice a = {a:g} through the Double Gauss (stop at F1U): who meets where")
    ax.legend(fontsize=7, loc="upper left")
    lo, hi = real.distance_mm[0] - 0.4, real.distance_mm[0] + real.spread_mm[0] + 0.4
    axz.set_xlim(min(lo, para.distance_mm - 0.1), max(hi, para.distance_mm + 0.1))
    axz.set_ylim(-60, 60)
    axz.set_title(f"close-up: the inner pairs cross over {real.spread_mm[0]:.3f} mm (spread_mm)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    for f_s in (2.749, 1.623):
        for extra in (0.0, 10.0, 20.0):
            for kind in ("telecentric", "own"):
                cam = camera(kind, extra, f_s)
                d_a = "∞" if cam.telecentric else f"{cam.main_optics.exit_pupil_distance_mm:.3f} mm"
                stop = "stop at F1U (the paper’s experiment)" if kind == "telecentric" else "own stop"
                print(f"\n#### f_s = {f_s} mm, b_U = f_U + {extra:g} mm, {stop}, d_A = {d_a}\n")
                print(table(cam, [0, 1, 2, 3, 4, 5]))
    for extra in (0.0, 20.0):
        print(f"\n#### views, stop at F1U, b_U = f_U + {extra:g} mm\n")
        print(views_table(camera("telecentric", extra), [-12, -1, 0, 1, 12]))
    figure_deviation(DOCS / "real-lens.png")
    figure_bundle(DOCS / "real-lens-bundle.png")


if __name__ == "__main__":
    main()
