#!/usr/bin/env python
"""Benchmark of ``lfproc.depth_map``: accuracy on rendered scenes with known depth, and speed on an Illum-sized
light field; writes ``docs/benchmarks-depth.md``.

Accuracy (on textured lenses off the borders and away from occlusions, see ``region``):
median |distance error| as a share of the slice DOF at the true distance, BadPix (share off by more
than that DOF, as the HCI 4D light field benchmark reports it), share inside the estimate's own
[near, far], share unknown (NaN); on the textureless card the share unknown and the share confidently
wrong (confidence ≥ 0.5 and off by more than the DOF). Each scene is measured on the simulator's ideal
views (the method alone) and on the decoded capture (method + decoding), and compared with the naive
baseline: the sharpest (3 × 3 gradient energy) of slices 0.05 apart in a, all views.

Speed: 15 × 15 views of 434 × 625 × 3 float32 (a Lytro Illum decode) with smooth random content on two
surfaces (a = 0.25 and 1.75, so the coarse pass keeps about two thirds of the default range); the
time of each step, against one refocused slice of the same light field measured in the same run, and
against the straightforward implementation of the same sweep (one refocus call per slice, all views).

Usage: ``python scripts/bench_depth.py [--repeats N] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from benchlib import fmt, machine_info, markdown_table
from lfproc.camera import MainLens

TARGET_MEDIAN_DOF = 0.05
TARGET_BADPIX = 0.05
TARGET_INSIDE = 0.90
TARGET_SECONDS = 10.0
NAIVE_STEP = 0.05


def test_camera():
    from lfproc import Camera

    return Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), black_level=64, white_level=16383, cfa="RGGB", name="depth-bench")


def scenes(camera):
    """(name, Scene, {plane index: role}) of each accuracy scene; roles "textured" or "textureless"."""
    from lfproc import geometry
    from lfproc.simulate import Noise, Plane, Scene, Uniform

    d = lambda a: float(geometry.slice_distance_mm(camera, a))
    out = [("cards: textured wall a=0.57, textured card a=1.43, textureless card a=1.10",
            Scene((Plane(d(1.43), Noise(feature_mm=3.0, seed=4, low=0.15, high=0.9), region_mm=(-60, -2, -60, 60)),
                   Plane(d(1.10), Uniform(0.5), region_mm=(4, 60, 4, 60)),
                   Plane(d(0.57), Noise(feature_mm=6.0, seed=7, low=0.1, high=0.9))), background=0.05),
            {0: "textured", 1: "textureless", 2: "textured"})]
    for a in (0.33, 0.86, 1.64):
        out.append((f"one plane a={a}", Scene((Plane(d(a), Noise(feature_mm=4.0 * d(a) / 600.0, seed=11,
                                                                     low=0.1, high=0.9)),)), {0: "textured"}))
    if "tilt_deg" in getattr(Plane, "__dataclass_fields__", {}):  # the simulator's tilted planes, once they exist
        for tilt, feature, a in ((60.0, 10.0, 1.23), (70.0, 5.0, 1.0)):
            out.append((f"plane tilted {tilt:.0f} deg about y, {feature:.0f} mm texture, centre a={a}",
                        Scene((Plane(d(a), Noise(feature_mm=feature, seed=9, low=0.1, high=0.9),
                                     tilt_deg=(tilt, 0.0)),), background=0.05), {0: "textured"}))
    return out


def truth_distance(sim) -> np.ndarray:
    """Per lens, the distance of the surface the central view sees (the simulator's ground truth)."""
    if getattr(sim, "depth_mm", None) is not None:
        return np.asarray(sim.depth_mm, dtype=np.float64)
    distances = np.array([p.distance_mm for p in sim.planes] + [np.nan])
    return distances[np.where(sim.plane_label >= 0, sim.plane_label, len(sim.planes))]


def region(sim, index, camera, a_spread):
    """Lenses of plane ``index`` that every view sees unoccluded (eroded by c·Δa + 2 lenses), off the borders."""
    from scipy import ndimage

    margin = math.ceil(camera.center_index * a_spread) + 2
    return ndimage.binary_erosion(sim.plane_label == index, iterations=margin, border_value=0)


def naive_estimate(lf, a_low, a_high):
    """The sharpest of slices NAIVE_STEP apart (3 × 3 gradient energy of the refocused luminance)."""
    from scipy import ndimage

    import lfproc

    a_values = np.round(np.arange(a_low, a_high + 1e-9, NAIVE_STEP), 10)
    stack = lfproc.refocus(lf, a_values)
    y = stack.mean(axis=-1)
    gy, gx = np.gradient(y, axis=(1, 2))
    energy = ndimage.uniform_filter(gx * gx + gy * gy, size=(1, 3, 3))
    return a_values[np.argmax(energy, axis=0)]


def render_and_decode(camera, scene, ideal_views: bool = True):
    """A 400 × 560 px render of ``scene`` (shot noise at 100 000 photons) and its light field, decoded from
    16-bit PNG files as the commands read them."""
    from lfproc import simulate
    from lfproc.api import DecodeSetup
    from lfproc.io import read_capture, write_image

    sim = simulate.render(camera, scene, (400, 560), rotation_deg=0.2, offset_px=(0.3, -0.2),
                          shot_noise_photons=100000, seed=3, ideal_views=ideal_views)
    with tempfile.TemporaryDirectory() as tmp:
        write_image(os.path.join(tmp, "c.png"), sim.raw)
        write_image(os.path.join(tmp, "w.png"), sim.white)
        setup = DecodeSetup(camera, sim.grid, read_capture(os.path.join(tmp, "w.png"), camera))
        return sim, setup.decode(os.path.join(tmp, "c.png"))


def accuracy_rows(quick: bool):
    import lfproc
    from lfproc import LightField, geometry

    camera = test_camera()
    rows, textureless_rows = [], []
    for name, scene, roles in scenes(camera)[: 2 if quick else None]:
        sim, decoded = render_and_decode(camera, scene)
        truth = truth_distance(sim)
        truth_a = np.where(np.isfinite(truth), geometry.refocus_parameter(camera, np.nan_to_num(truth, nan=1e9)), np.nan)
        finite_a = truth_a[np.isfinite(truth_a)]
        spread = float(finite_a.max() - finite_a.min()) if finite_a.size else 0.0
        ideal = LightField.from_views(sim.ideal_views, camera, sim.grid)
        for source, lf, options in (("ideal views", ideal, {}), ("decoded", decoded, {}),
                                    ("decoded, outer ring of views in", decoded, {"outer_views": True})):
            depth_map = lfproc.depth_map(lf, **options)
            naive_a = naive_estimate(lf, float(depth_map.a_searched[0]), float(depth_map.a_searched[-1]))
            naive_d = geometry.slice_distance_mm(camera, naive_a)
            for index, role in roles.items():
                plane_name = sim.planes[index].name or f"plane {index}"
                if role == "textured":
                    mask = region(sim, index, camera, spread) & np.isfinite(truth)
                    if "tilted" in name:  # one plane, no occlusion: only the borders and the background go
                        mask = region(sim, index, camera, 0.2) & np.isfinite(truth)
                    ref = geometry.slice_geometry(camera, truth_a[mask])
                    err = (depth_map.distance_mm[mask] - ref.distance_mm) / ref.dof_mm
                    naive_err = (naive_d[mask] - ref.distance_mm) / ref.dof_mm
                    inside = (depth_map.near_mm[mask] <= ref.distance_mm) & (ref.distance_mm <= depth_map.far_mm[mask])
                    rows.append([name, source, f"a={np.median(truth_a[mask]):.2f}", str(int(mask.sum())),
                                 float(np.nanmedian(np.abs(err))), float(np.mean(~(np.abs(err) <= 1.0))),
                                 float(np.mean(inside)), float(np.mean(np.isnan(err))),
                                 float(np.median(np.abs(naive_err))), float(np.mean(~(np.abs(naive_err) <= 1.0))),
                                 float(np.nanmedian(err))])
                else:
                    from scipy import ndimage

                    mask = ndimage.binary_erosion(sim.plane_label == index, iterations=1, border_value=0)
                    ref = geometry.slice_geometry(camera, truth_a[mask])
                    wrong = ~(np.abs(depth_map.distance_mm[mask] - ref.distance_mm) <= ref.dof_mm)
                    confident = depth_map.confidence[mask] >= 0.5
                    textureless_rows.append([name, source, plane_name, str(int(mask.sum())),
                                             float(np.mean(np.isnan(depth_map.distance_mm[mask]))),
                                             float(np.mean(confident)), float(np.mean(wrong & confident))])
    return rows, textureless_rows


def illum_light_field():
    from scipy import ndimage

    from lfproc import Camera, LightField

    camera = Camera(0.0014, 0.02, 0.04, MainLens(30.0, 30.0, f_number=2.0), cfa="GRBG", grid="hexagonal", micro_image_px=15, name="illum-like")
    rng = np.random.default_rng(0)
    pad = 24
    base = ndimage.gaussian_filter(rng.random((434 + 2 * pad, 625 + 2 * pad, 3), dtype=np.float32), (1.5, 1.5, 0))
    views = np.empty((15, 15, 434, 625, 3), np.float32)
    half = 312
    for ky in range(15):
        for kx in range(15):  # two surfaces: a = 0.25 (left half) and a = 1.75 (right half), whole-lens shifts
            for a, cols in ((0.25, slice(0, half)), (1.75, slice(half, 625))):
                dy, dx = round(a * (7 - ky)), round(a * (7 - kx))
                window = base[pad - dy:pad - dy + 434, pad - dx:pad - dx + 625]
                views[ky, kx, :, cols] = window[:, cols]
    return LightField.from_views(views, camera)


def median_time(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), result


def speed_rows(repeats: int):
    import lfproc
    from lfproc import geometry
    from lfproc.depth._cost import sweep_luminance, sweep_views

    lf = illum_light_field()
    camera = lf.camera
    one_linear, _, _ = median_time(lambda: lfproc.refocus(lf, 0.5), repeats)
    one_cubic, _, _ = median_time(lambda: lfproc.refocus(lf, 0.5, interpolation="cubic"), repeats)
    cases = [("no range: a_inf .. a_inf + 3, coarse pass", {}),
             ("no range, no coarse pass", {"coarse_pass": False}),
             ("--depth-range for a in [0, 1]", {"depth_range_mm": (float(geometry.slice_distance_mm(camera, 1.0)),
                                                                   float(geometry.slice_distance_mm(camera, 0.0)))})]
    rows, steps = [], []
    for label, kwargs in cases:
        total, best, depth_map = median_time(lambda kwargs=kwargs: lfproc.depth_map(lf, **kwargs), repeats)
        rows.append([label, str(len(depth_map.a_searched)), str(depth_map.view_step), total, best, total / one_linear,
                     "PASS" if total <= TARGET_SECONDS else "FAIL"])
        steps.append((label, depth_map.timings_s))
    # the straightforward sweep: one refocus call per slice over all views (no fusion, no view step)
    a_values = lfproc.depth_map(lf, **cases[2][1]).a_searched
    full = sweep_views(sweep_luminance(lf.views, 1, None, geometry.views_inside_aperture(camera)))
    t0 = time.perf_counter()
    for a in a_values:
        lfproc.refocus(full, float(a), interpolation="cubic")
    straightforward = time.perf_counter() - t0
    return rows, steps, one_linear, one_cubic, straightforward, len(a_values)


def speed_json(info, speed, steps, one_linear, one_cubic, straightforward) -> dict:
    """The speed section as plain data (docs/benchmarks-depth.json)."""
    keys = ("case", "sweep_slices", "view_step", "median_s", "min_s", "ratio_to_one_slice", "target")
    return {"date": info["date"], "cpus_usable": info["cpus_usable"], "load_average_start": info["load_average_start"],
            "light_field": "15 x 15 x 434 x 625 x 3 float32 (0.73 GB), illum-like camera, two surfaces a = 0.25, 1.75",
            "target_s": TARGET_SECONDS, "one_slice_linear_s": one_linear, "one_slice_cubic_s": one_cubic,
            "speed": [dict(zip(keys, [row[0], int(row[1]), int(row[2]), *row[3:]])) for row in speed],
            "steps_s": {label: dict(timings) for label, timings in steps},
            "straightforward_sweep_s": straightforward}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="two accuracy scenes only")
    parser.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks-depth.md"))
    parser.add_argument("--json", default=os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks-depth.json"),
                        help="the speed results as JSON (the source of the depth-map times quoted in README.md and "
                             "docs/, checked by tests/test_doc_numbers.py)")
    args = parser.parse_args()
    start = time.perf_counter()
    info = machine_info()
    acc, textureless = accuracy_rows(args.quick)
    speed, steps, one_linear, one_cubic, straightforward, k_straight = speed_rows(args.repeats)
    lines = ["# Depth benchmark (`lfproc.depth_map`)", "",
             (f"Generated by `python scripts/bench_depth.py` on {info['date']} in {time.perf_counter() - start:.0f} s. "
             "Numbers move with the machine and its load; rerun to compare."), "",
             markdown_table(["machine", ""], [["CPU", info["cpu_model"]], ["CPUs usable", str(info["cpus_usable"])],
                                              ["numba threads", str(info["numba_threads"])],
                                              ["load average at start", ", ".join(f"{v:.2f}" for v in info["load_average_start"])],
                                              ["numpy / numba", f"{info['numpy']} / {info['numba']}"]]), "",
             "## Accuracy on rendered scenes", "",
             ("Defaults (the outer ring of views left out, coarse pass). Camera: 9 µm pixels under 100 µm lenses (11.1 px, resampled to m̂ = 11), f_U = 50 mm focused at "
             "infinity, f/4, RGGB, 400 × 560 px sensor (35 × 49 lenses), shot noise at 100 000 photons full scale. "
             "Lenses: textured, off the borders and farther than c·Δa + 2 lenses from any occlusion edge. "
             f"Targets: median ≤ {TARGET_MEDIAN_DOF:.0%} of the DOF, BadPix ≤ {TARGET_BADPIX:.0%}, inside [near, far] "
             f"≥ {TARGET_INSIDE:.0%}. Naive: the sharpest of slices {NAIVE_STEP} apart in a. Signed bias > 0: too far."), "",
             markdown_table(["scene", "views", "truth", "lenses", "median \\|err\\|/DOF", "BadPix", "inside",
                             "unknown", "naive median/DOF", "naive BadPix", "signed median/DOF"], acc), "",
             "Textureless card (every lens of it, edges included):", "",
             markdown_table(["scene", "views", "plane", "lenses", "unknown (NaN)", "confidence ≥ 0.5",
                             "confident and wrong"], textureless), "",
             "## Speed on an Illum-sized light field", "",
             (f"15 × 15 × 434 × 625 × 3 float32 (0.73 GB), illum-like camera (m̂ = 15, f/2: 177 of 225 views inside the "
             f"stop), smooth random content on two surfaces at a = 0.25 and 1.75. Median of {args.repeats} runs after a warm-up. One refocused slice of the same light field, "
             f"same run: {fmt(one_linear)} s linear, {fmt(one_cubic)} s cubic. Target ≤ {TARGET_SECONDS:.0f} s."), "",
             markdown_table(["case", "sweep slices", "view step", "time s", "min s", "× one slice", "target"], speed), ""]
    for label, timings in steps:
        total = sum(timings.values())
        lines += [f"Steps, {label}:", "",
                  markdown_table(["step", "s", "share"], [[k, v, f"{v / total:.0%}"] for k, v in timings.items()]), ""]
    lines += [(f"Straightforward sweep for comparison (the {k_straight} slices of the last case, one refocus call per "
              f"slice, all views, cubic): {fmt(straightforward)} s for the cost volume alone, "
              f"{straightforward / speed[2][3]:.1f} × the depth map's whole time."), ""]
    with open(args.out, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines))
    with open(args.json, "w", encoding="utf-8") as fh:
        json.dump(speed_json(info, speed, steps, one_linear, one_cubic, straightforward), fh, indent=1)
        fh.write("\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
