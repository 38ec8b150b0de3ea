"""The figure of docs/exit-pupil.md: how far the telecentric model misplaces slices of an Illum-like camera.

For the Illum-like camera (``samples/cameras/illum-like.toml``: exit pupil 46 mm in front of the MLA)
focused at 0.5, 1 and 3 m, every slice a is placed by the finite-exit-pupil model (truth) and by the
2014 telecentric model (the same camera file without ``exit_pupil_distance_mm``). The curves show the
telecentric distance error in per cent against the true distance; the shaded band is each slice's own
DOF (half width, in per cent of its distance), so where a curve leaves the band the telecentric model
puts the slice outside its own depth of field.

Run: ``PYTHONPATH=. python scripts/exit_pupil_figure.py`` -> docs/exit-pupil-error.png (and prints a table).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from lfproc.io import focused_at
from lfproc import Camera, geometry

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "exit-pupil-error.png"


def curves(focus_mm: float):
    finite = Camera.focused_at(from_toml(ROOT / "samples" / "cameras" / "illum-like.toml"), focus_mm)
    tele = dataclasses.replace(finite, exit_pupil_distance_mm=math.inf)
    a = np.linspace(geometry.infinity_parameter(finite) + 1e-3, 12.0, 4000)
    true = geometry.slice_geometry(finite, a)
    told = geometry.slice_distance_mm(tele, a)
    ok = np.isfinite(true.distance_mm) & np.isfinite(told) & (true.distance_mm < 30000)
    error = 100.0 * (told[ok] / true.distance_mm[ok] - 1.0)
    half_dof = 100.0 * 0.5 * (true.far_mm[ok] - true.near_mm[ok]) / true.distance_mm[ok]
    return true.distance_mm[ok], error, half_dof, a[ok]


def main():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 3.9), dpi=90)
    rows = []
    for focus, colour in ((500.0, "tab:blue"), (1000.0, "tab:orange"), (3000.0, "tab:green")):
        d, err, half, a = curves(focus)
        ax.plot(d, err, color=colour, lw=1.6, label=f"focused at {focus / 1000:g} m")
        ax.fill_between(d, -half, half, color=colour, alpha=0.12, lw=0)
        for target in (300.0, 500.0, 1000.0, 2000.0, 5000.0):
            k = int(np.argmin(np.abs(d - target)))
            if abs(d[k] / target - 1) < 0.02:
                rows.append((focus, d[k], a[k], err[k], half[k]))
    ax.set_xscale("log")
    ax.set_xlim(250, 20000)
    ax.set_ylim(-12, 12)
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel("true slice distance from the sensor [mm]")
    ax.set_ylabel("telecentric model error [%]")
    ax.set_title("Illum-like camera, exit pupil 46 mm: the telecentric model's error\n"
                 "shaded: each slice's own DOF (half width)", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(OUT, format="png")
    plt.close(fig)
    print("| focus [m] | true distance [mm] | a | telecentric error [%] | half DOF [%] |")
    print("| --- | --- | --- | --- | --- |")
    for focus, d, a, err, half in rows:
        print(f"| {focus / 1000:g} | {d:.0f} | {a:.3f} | {err:+.2f} | {half:.2f} |")
    print(f"\n{OUT.name}: {OUT.stat().st_size / 1000:.1f} kB")


if __name__ == "__main__":
    main()
