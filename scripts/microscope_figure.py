"""The figure and the NA table of docs/microscope.md: the light-field microscope's ray model, and where
the paraxial map from a to depth leaves a slice's depth of field (so aplanatic refocusing is on).

Left: a paraxial ray trace (lfproc.geometry's transfer, drawn lens by lens) of a point z above the
native object plane through objective, stop and tube lens: the rays meet w = z·M²/n behind the micro
lens array, which the views see as slice a = w/(m̂·f_s). Right: for objectives from NA 0.3 to 1.4 with
lenslets matched to their NA, the depth error of the paraxial map, e·|z| (e = paraxial_depth_error),
against the DOF of the slice there; where the error exceeds the DOF, refocusing follows the sine
condition by default.

Run: ``PYTHONPATH=. python scripts/microscope_figure.py`` -> docs/microscope-geometry.png (and prints the
markdown table of docs/microscope.md).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lfproc import Camera, geometry

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "microscope-geometry.png"

#: objectives of the table: (magnification, NA, immersion index, medium)
OBJECTIVES = [(10, 0.3, 1.0, "air"), (20, 0.5, 1.33, "water"), (40, 0.8, 1.33, "water"),
              (40, 1.0, 1.33, "water"), (60, 1.2, 1.333, "water"), (100, 1.4, 1.515, "oil")]


def matched_camera(m: float, na: float, n: float, pitch_mm: float = 0.1, pixel_mm: float = 0.0065) -> Camera:
    """A microscope whose lenslets fill the objective's NA: f_s = pitch·M/(2·NA) (15 samples per lens)."""
    f_s = pitch_mm * m / (2.0 * na)
    return Camera.from_toml_string(f"""[sensor]
pixel_pitch_mm = {pixel_mm}
[mla]
pitch_mm = {pitch_mm}
focal_length_mm = {f_s}
[microscope]
objective_magnification = {m}
numerical_aperture = {na}
immersion_index = {n}
tube_lens_focal_length_mm = 200.0
wavelength_nm = 520
""", f"{m:g}x/{na:g}")


def table() -> str:
    rows = ["| objective | medium | µm per unit a | DOF at a = 0 [µm] | paraxial error e | error at a = 1 [µm] "
            "| DOF at a = 1 [µm] | paraxial error > DOF beyond | aplanatic by default |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for m, na, n, medium in OBJECTIVES:
        cam = matched_camera(m, na, n)
        zeta, e = geometry.z_per_a_um(cam), geometry.paraxial_depth_error(cam)
        dof0, dof1 = (float(geometry.slice_geometry(cam, a).dof_um) for a in (0.0, 1.0))
        # |z| where e·|z| reaches the DOF there (the DOF grows linearly in |a| between 0 and 1)
        slope = (dof1 - dof0) / zeta
        beyond = dof0 / (e - slope) if e > slope else float("inf")
        where = f"\\|z\\| > {beyond:.3g} µm" if np.isfinite(beyond) else "never"
        rows.append(f"| {m:g}x/{na:g} | {medium} | {zeta:.4g} | {dof0:.3g} | {e:.3f} | {e * zeta:.3g} | {dof1:.3g} | "
                    f"{where} | {'yes' if geometry.uses_aplanatic(cam) else 'no'} |")
    return "\n".join(rows)


def _trace(cam: Camera, z_mm: float, slope: float):
    """Points (x along the axis, y) of a ray from the axial point z through the microscope to the sensor."""
    scope = cam.main_optics
    n, f_o, f_t = scope.immersion_index, scope.objective_focal_length_mm, scope.tube_lens_focal_length_mm
    x, y, u = -n * f_o + z_mm, 0.0, slope
    xs, ys = [x], [y]
    y += (n * f_o - z_mm) * u
    x = 0.0
    xs.append(x); ys.append(y)
    u = n * u - y / f_o
    for length, power in ((f_o + f_t, 1.0 / f_t), (f_t, 0.0)):
        y += length * u
        x += length
        xs.append(x); ys.append(y)
        u -= y * power
    return np.array(xs), np.array(ys)


def main():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 3.6), dpi=80)
    cam = matched_camera(20, 0.5, 1.33)
    scope = cam.main_optics
    f_o, f_t = scope.objective_focal_length_mm, scope.tube_lens_focal_length_mm
    z_mm = 0.4                              # exaggerated so that the meeting point shows
    for slope in np.linspace(-0.3, 0.3, 7):
        for z, colour in ((0.0, "0.6"), (z_mm, "tab:red")):
            xs, ys = _trace(cam, z, slope)
            left.plot(xs, ys, color=colour, lw=0.8)
    for x, label in ((0.0, "objective"), (f_o, "stop"), (f_o + f_t, "tube lens"), (f_o + 2 * f_t, "MLA")):
        left.axvline(x, color="k", lw=1.2 if label != "stop" else 0.6, ls="-" if label != "stop" else ":")
        left.text(x + 4, 0.9 * left.get_ylim()[0], label, ha="left", fontsize=8, rotation=90, va="bottom")
    left.set_xlabel("along the axis [mm] (objective at 0, sample left)")
    left.set_title("20x/0.5: a point z above the native plane (red)\nmeets z·M²/n behind the MLA", fontsize=9)
    left.set_yticks([])
    nas = np.linspace(0.2, 1.4, 25)
    errors, dofs = [], []
    for na in nas:
        n = 1.33 if na < 1.25 else 1.515
        c = matched_camera(60, na, n)
        errors.append(geometry.paraxial_depth_error(c) * geometry.z_per_a_um(c))
        dofs.append(float(geometry.slice_geometry(c, 1.0).dof_um))
    right.semilogy(nas, errors, "tab:red", label="paraxial depth error at a = 1")
    right.semilogy(nas, dofs, "k", label="DOF of the slice at a = 1")
    right.set_xlabel("NA (60x, matched lenslets; water, oil above 1.25)")
    right.set_ylabel("µm")
    right.legend(fontsize=8)
    right.set_title("aplanatic refocusing is on\nwhere red exceeds black", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT)
    print(f"wrote {OUT}")
    print(table())


if __name__ == "__main__":
    main()
