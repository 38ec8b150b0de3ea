"""Evidence for the DOF beyond the focus distance (issue 12): renders of planes around integer slices.

A Lytro-like telecentric camera (13 px micro images, f/2, focused at 600 mm) sees a noise-textured
plane at the depth of slice a_z (texture scaled with the magnification, so every plane looks alike in
the views). Two measurements, both free of interpolation:

1. the sharpness (gradient energy) of the central view itself against a_z. The paper's border-ray
   pairs imply a beam 1 + a_z lenses wide (zero at a_z = −1, so the sharpest view there); beams that
   fill their lens and pixel are 1 + |a_z| wide, as sharp at −a_z as at a_z;
2. the sharpness (gradient energy) of the integer slices a_s = 1, 0, −1, −2 against a_z, and the
   half-maximum width of that curve in a, next to the DOF width in a of both models.

Run: ``PYTHONPATH=. python scripts/beyond_focus.py`` (about a minute); prints a Markdown table.
"""

from __future__ import annotations

import json
import sys

import numpy as np

import lfproc
from lfproc.io import focused_at
from lfproc import Camera, geometry, simulate
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

CAMERA = focused_at(Camera(0.0014, 0.0182, 0.0364, MainLens(30.0, 30.0, f_number=2.0), micro_image_px=13,
                           name="lytro-like"), 600.0)
LENSES = 30


def lens_on_plane_mm(camera: Camera, a_z: float) -> float:
    """Plane width seen by one lens of the central view at slice a_z's depth."""
    z = geometry.slice_distance_mm(camera, a_z) - camera.main_optics.sensor_path_mm(camera.mla_path_mm)
    return camera.mla_pitch_mm * abs(1.0 - z / camera.main_optics.focal_length_mm)


def render_views(camera: Camera, a_z: float, texture) -> np.ndarray:
    d = geometry.slice_distance_mm(camera, a_z)
    scene = Scene((Plane(d, texture),))
    views, _, _ = simulate.render_ideal_views(camera, scene, (LENSES * camera.m_hat, LENSES * camera.m_hat),
                                              rim_radius_mm=None)
    return views


def central_view_energy(camera: Camera, a_z: float) -> float:
    """Gradient energy of the central view alone (no refocusing, no interpolation) of a plane at slice a_z."""
    views = render_views(camera, a_z, Noise(1.5 * lens_on_plane_mm(camera, a_z), seed=3))
    c = camera.center_index
    return gradient_energy(views[c, c])


def gradient_energy(image: np.ndarray, border: int = 8) -> float:
    img = image[border:-border, border:-border, 0]
    return float((np.diff(img, axis=0) ** 2).mean() + (np.diff(img, axis=1) ** 2).mean())


def sharpness_curves(camera: Camera, slices, a_grid):
    energy = np.zeros((len(a_grid), len(slices)))
    for i, a_z in enumerate(a_grid):
        views = render_views(camera, a_z, Noise(1.5 * lens_on_plane_mm(camera, a_z), seed=3))
        out = lfproc.refocus(lfproc.LightField.from_views(views, camera), list(slices), interpolation="nearest")
        energy[i] = [gradient_energy(img) for img in out]
    return energy


def paper_dof_a(a: float, c: int) -> tuple[float, float]:
    """The 2014 paper's DOF limits in a for every a: (2ac − 1)/(2c + 1) and (2ac + 1)/(2c − 1)."""
    return (2 * a * c - 1) / (2 * c + 1), (2 * a * c + 1) / (2 * c - 1)


def half_max_width(a_grid, curve, a_s) -> float:
    """Width in a of the connected run around a_s where the curve is at least half its value at a_s."""
    k = int(np.argmin(np.abs(a_grid - a_s)))
    ok = curve >= 0.5 * curve[k]
    lo = hi = k
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi < len(ok) - 1 and ok[hi + 1]:
        hi += 1
    def cross(i, j):  # linear interpolation of the half-level crossing between grid points i (in) and j (out)
        level = 0.5 * curve[k]
        t = (curve[i] - level) / (curve[i] - curve[j])
        return a_grid[i] + t * (a_grid[j] - a_grid[i])
    left = cross(lo, lo - 1) if lo > 0 else a_grid[0]
    right = cross(hi, hi + 1) if hi < len(ok) - 1 else a_grid[-1]
    return float(right - left)


def main() -> dict:
    cam, c = CAMERA, CAMERA.center_index
    edge = {a_z: central_view_energy(cam, a_z) for a_z in (2.0, 1.0, 0.0, -1.0, -2.0)}
    slices = (1.0, 0.0, -1.0, -2.0)
    a_grid = np.round(np.arange(-2.5, 1.5001, 0.05), 3)
    energy = sharpness_curves(cam, slices, a_grid)
    rows = []
    for j, a_s in enumerate(slices):
        geo = geometry.slice_geometry(cam, a_s)
        lo, hi = (geometry.refocus_parameter(cam, geo.far_mm), geometry.refocus_parameter(cam, geo.near_mm))
        p_lo, p_hi = paper_dof_a(a_s, c)
        rows.append(dict(a=a_s, distance_mm=geo.distance_mm, measured_width_a=half_max_width(a_grid, energy[:, j], a_s),
                         model_width_a=hi - lo, paper_width_a=p_hi - p_lo, near_mm=geo.near_mm, far_mm=geo.far_mm,
                         paper_near_mm=float(geometry.slice_distance_mm(cam, max(p_lo, p_hi))),
                         paper_far_mm=float(geometry.slice_distance_mm(cam, min(p_lo, p_hi)))))
    return dict(central_view_energy=edge, slices=rows, a_grid=a_grid.tolist(), energy=energy.tolist())


if __name__ == "__main__":
    result = main()
    print("| a_z | central view gradient energy |\n| --- | --- |")
    for a_z, w in result["central_view_energy"].items():
        print(f"| {a_z:+.0f} | {w:.5f} |")
    print("\n| slice a | distance [mm] | measured half-max width in a | DOF width in a (this model) | "
          "ratio | paper's DOF width in a | this model near..far [mm] | paper near..far [mm] |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in result["slices"]:
        print(f"| {r['a']:+.0f} | {r['distance_mm']:.1f} | {r['measured_width_a']:.3f} | {r['model_width_a']:.3f} | "
              f"{r['measured_width_a'] / r['model_width_a']:.2f} | {r['paper_width_a']:+.3f} | "
              f"{r['near_mm']:.1f}..{r['far_mm']:.1f} | {r['paper_near_mm']:.1f}..{r['paper_far_mm']:.1f} |")
    if len(sys.argv) > 1:
        with open(sys.argv[1], "w") as fh:
            json.dump(result, fh, indent=1)
