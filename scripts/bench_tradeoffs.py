#!/usr/bin/env python
"""The speed–accuracy trade on today's code, measured in one run: ``docs/speed-accuracy.{md,json}``.

Each setting's time (median of repeats, CPU time beside it, and a floor measured in the same run) and its
accuracy against an exact reference, reusing the stages of the other benchmark scripts:

* **decode** (``bench_decode``): interpolation nearest / linear / cubic / lanczos and demosaic fast /
  careful on the Lytro-Illum-sized capture of ``benchsim``; floor: one copy of the sensor. Accuracy: PSNR
  against the simulator's ideal views (``bench_decode.psnr_row``).
* **refocus** (the cases of ``bench_refocus.stage_refocus``, ``bench_interpolation.sweep_errors``): integer a (gather), real a
  with nearest / linear / cubic / cubic-spline, upsample 2, many slices in one call, on the decoded views;
  floor: one read of the views. Accuracy: PSNR on an exact light field of a textured plane
  (``benchlib.plane_light_field``) and the bias of the sharpest slice of a sweep from the true a on exact
  plane views (``lfproc.simulate.plane_views``, photographic and microscope sampling).
* **depth** (``bench_depth``): the default search and its faster / slower settings, timed on the
  Illum-sized light field; accuracy on the rendered, decoded cards scene with known depths.
* **deconvolution** (microscopes): iterations 4 / 8 / 16 at super-resolution 3 and 5, and without the
  anti-aliasing filter, on four wave-rendered beads (``tests/test_deconvolve.py``); accuracy: where the
  brightest voxel near each bead lies.
* **geometry models**: paraxial (the paper's, exit pupil at infinity), the exit-pupil model, real rays
  through the Double Gauss prescription, against optiland's independent exact trace of the same rays
  (``tests/test_real_lens.py``); the paraxial model also against the paper's Zemax numbers (Table 2).
  Time per 1e6 slices; floor: one numpy pass over 1e6 values.

Usage: ``python scripts/bench_tradeoffs.py [--quick] [--out DIR]``. The full run writes to ``docs/``; it took
10 minutes of wall time and 6.8 minutes of CPU time on 2 cores at a load of 5–9 (2.4 GB peak). ``--quick``
(about a minute, small captures, one repeat) writes to a temporary folder unless ``--out`` is given.
``python scripts/bench_tradeoffs.py --page-only`` rewrites the page from the JSON.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import math
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_decode  # noqa: E402  (this folder)
import bench_depth  # noqa: E402
import benchlib as bl  # noqa: E402
import benchsim as suite  # noqa: E402

ROOT = suite.ROOT
sys.path.insert(0, str(ROOT / "tests"))
DOCS = ROOT / "docs"
COMMAND = "python scripts/bench_tradeoffs.py"
GEOMETRY_A = {"own stop": (1.0, 2.0), "stop at F1U": (1.0, 2.0, 3.0, 4.0, 5.0)}   # own stop: a ≥ 3 lies inside the lens
DEPTH_SETTINGS = (("default", {}), ("linear interpolation", {"interpolation": "linear"}),
                  ("no half apertures", {"half_apertures": False}), ("no coarse pass", {"coarse_pass": False}))
REFOCUS_CASES = (("integer a", suite.INTEGER_A, "linear", 1), *(("real a", suite.REAL_A, i, 1) for i in
                 ("nearest", "linear", "cubic", "cubic-spline")), ("real a", suite.REAL_A, "cubic-spline", 2))
MANY_SLICES = 11
DECONV_BEADS = ((-41.0, 26.0, -22.5), (31.0, -34.0, 18.0), (-30.0, -38.0, 32.0), (42.0, 30.0, -31.0))  # x, y, z µm
DECONV_LENSES = (25, 25)
DECONV_SUPERRES = (3, 5)
DECONV_ITERATIONS = (4, 8, 16)
DECONV_SLACK = 1.1      # "as well as any": a worst lateral error within 10 % of the smallest measured
PREVIEW_SLACK = 1.1     # a preview decode may take this much longer than the fastest if it is more accurate
PREVIEW_MIN_DB = 40.0   # a preview still looks like the scene: 40 dB, the usual threshold of visible error


def _finite(value):
    """JSON has no infinity: an exact result (PSNR ∞) is stored as None."""
    return None if value is None or not math.isfinite(value) else float(value)


# ----------------------------------------------------------------------------- decode
def decode_section(s: suite.Settings) -> tuple[dict, np.ndarray]:
    from lfproc.decode import make_decoder

    big = suite.big_capture(s)
    camera, raw, white, grid = big["camera"], big["raw"], big["white"], big["sim"].grid
    big = None
    decoder, prepare_s = bl.time_once(lambda: make_decoder(white, grid, camera.m_hat, camera.cfa))
    floor = bl.measure(lambda: raw.copy(), s.cheap_repeats, memory=False)
    rows, views = [], None
    for interp, method in [(i, "fast") for i in suite.INTERPOLATIONS] + [("linear", "careful")]:
        dec = dataclasses.replace(decoder, interpolation=interp, demosaic_method=method)
        timing, result = bl.measure_keeping(lambda: dec(raw), s.repeats, memory=False)
        rows.append({"interpolation": interp, "demosaic": method, "timing": timing.as_dict(),
                     "ratio_to_floor": timing.median_s / floor.median_s})
        suite.log(f"  decode {interp}/{method}: {timing.median_s:.2f} s")
        if (interp, method) == ("linear", "fast"):
            views = result
    mono = bench_decode.render_psnr_capture(suite.paper_9um_camera(), s)
    accuracy = [bench_decode.psnr_row("mono", mono, interp, "fast") for interp in suite.INTERPOLATIONS]
    bayer = bench_decode.render_psnr_capture(suite.paper_9um_camera("RGGB"), s)
    accuracy += [bench_decode.psnr_row("RGGB", bayer, "linear", method) for method in ("fast", "careful")]
    return {"sensor_shape": list(raw.shape), "cfa": camera.cfa, "views_shape": list(views.shape),
            "prepare_s": prepare_s, "floor": floor.as_dict(), "rows": rows,
            "accuracy_shape": list(s.psnr_shape), "accuracy": accuracy}, views


# ----------------------------------------------------------------------------- refocus
def refocus_section(views: np.ndarray, s: suite.Settings) -> dict:
    import bench_interpolation
    from lfproc import refocus
    from lfproc.simulate import plane_views

    floor = bl.measure(lambda: views.sum(axis=(0, 1)), s.cheap_repeats, memory=False)
    ny, nx = s.refocus_accuracy_lenses
    rows = []
    for label, a, interp, up in REFOCUS_CASES:
        timing = bl.measure(lambda: refocus(views, a, interp, up), s.cheap_repeats, memory=False)
        plane, texture = bl.plane_light_field(views.shape[0], (ny, nx), a)
        out = refocus(plane, a, interp, up)
        truth = texture(np.arange(out.shape[0])[:, None] / up, np.arange(out.shape[1])[None, :] / up)
        border = 2 * up   # cubic taps clamp at the array edge; compare the interior
        psnr = bl.psnr_db(out[border:-border, border:-border, 0], truth[border:-border, border:-border], peak=1.0)
        rows.append({"case": label, "a": a, "interpolation": interp if label == "real a" else "(gather)",
                     "upsample": up, "timing": timing.as_dict(), "ratio_to_floor": timing.median_s / floor.median_s,
                     "plane_psnr_db": _finite(psnr)})
        suite.log(f"  refocus {label} {interp} x{up}: {timing.median_s:.3f} s, plane {psnr:.1f} dB")
    many = np.round(np.linspace(-1.5, 1.5, MANY_SLICES) + 0.0037, 9)
    many_timing = bl.measure(lambda: refocus(views, many, "cubic-spline"), s.cheap_repeats, memory=False)
    # the sharpest slice of a sweep in steps of 0.001 against the true a of exact plane views
    kinds = {"photographic": (9, 1, bench_interpolation.photographic_a0(coarse=True)),
             "microscope": (15, 2, bench_interpolation.microscope_a0(coarse=True))}
    bias = {"half_width": 0.03}
    for kind, (m, seed, a0_values) in kinds.items():
        a0_values = a0_values[::4] if s.quick else a0_values
        errors = [bench_interpolation.sweep_errors(plane_views(m, 64, a0, seed=seed), a0, bias["half_width"]) for a0 in a0_values]
        bias[kind] = {"m_hat": m, "a0": [float(v) for v in a0_values],
                      "worst_abs_error": {name: max(abs(e[name]["band"]) for e in errors) for name in errors[0]}}
        suite.log(f"  sharpest-slice bias {kind}: {bias[kind]['worst_abs_error']}")
    return {"views_shape": list(views.shape), "gb": views.nbytes / 1e9, "floor": floor.as_dict(), "rows": rows,
            "plane_lenses": [ny, nx], "many_slices": {"count": MANY_SLICES, "interpolation": "cubic-spline",
                                                       "timing": many_timing.as_dict()},
            "bias": bias}


# ----------------------------------------------------------------------------- depth
def depth_accuracy() -> list[dict]:
    """Each setting on the rendered, decoded cards scene: errors on the textured planes' clear lenses."""
    from lfproc import geometry
    from lfproc.depth import depth      # the estimate itself (lfproc.depth_map adds the provenance of files)

    camera = bench_depth.test_camera()
    _, scene, roles = bench_depth.scenes(camera)[0]
    sim, lf = bench_depth.render_and_decode(camera, scene, ideal_views=False)
    truth = bench_depth.truth_distance(sim)
    truth_a = np.where(np.isfinite(truth), geometry.refocus_parameter(camera, np.nan_to_num(truth, nan=1e9)), np.nan)
    spread = float(np.nanmax(truth_a) - np.nanmin(truth_a))
    textured = [index for index, role in roles.items() if role == "textured"]
    every = np.isin(sim.plane_label, textured) & np.isfinite(truth)       # borders and occlusion edges too
    clear = np.zeros(truth.shape, bool)
    for index in textured:
        clear |= bench_depth.region(sim, index, camera, spread) & np.isfinite(truth)
    ref, ref_every = geometry.slice_geometry(camera, truth_a[clear]), geometry.slice_geometry(camera, truth_a[every])
    rows = []
    for label, options in DEPTH_SETTINGS:
        distance = depth(lf, **options).distance_mm
        err = (distance[clear] - ref.distance_mm) / ref.dof_mm
        err_every = (distance[every] - ref_every.distance_mm) / ref_every.dof_mm
        rows.append({"setting": label, "options": options, "lenses": int(clear.sum()),
                     "median_abs_error_dof": float(np.nanmedian(np.abs(err))),
                     "badpix": float(np.mean(~(np.abs(err) <= 1.0))), "coverage": float(np.mean(np.isfinite(err))),
                     "lenses_every": int(every.sum()), "within_dof_every": float(np.mean(np.abs(err_every) <= 1.0))})
        suite.log(f"  depth accuracy {label}: {rows[-1]}")
    return rows


def depth_section(s: suite.Settings) -> dict:
    import lfproc
    from lfproc.depth import depth

    lf = bench_depth.illum_light_field()
    if s.quick:
        lf = lfproc.LightField.from_views(np.ascontiguousarray(lf.views[:, :, :160, :240]), lf.camera)
    one_slice = bl.measure(lambda: lfproc.refocus(lf, 0.5, interpolation="cubic"), s.cheap_repeats, memory=False)
    speed = []
    for label, options in DEPTH_SETTINGS:
        timing, depth_map = bl.measure_keeping(lambda: depth(lf, **options), s.repeats, memory=False)
        speed.append({"setting": label, "timing": timing.as_dict(), "slices": int(len(depth_map.a_searched)),
                      "view_step": int(depth_map.view_step), "ratio_to_one_slice": timing.median_s / one_slice.median_s})
        suite.log(f"  depth {label}: {timing.median_s:.2f} s")
    return {"views_shape": list(lf.views.shape), "one_slice": one_slice.as_dict(), "speed": speed,
            "accuracy": depth_accuracy(), "scene": bench_depth.scenes(bench_depth.test_camera())[0][0]}


# ----------------------------------------------------------------------------- geometry
def geometry_section(s: suite.Settings) -> dict:
    from test_real_lens import _optiland_object_rays

    from lfproc import Camera
    from lfproc import geometry as g
    from lfproc.geometry._real_rays import slice_rays

    cameras = {"own stop": Camera.from_toml(suite.CAMERAS / "double-gauss-f100.toml"),
               "stop at F1U": Camera.from_toml(suite.CAMERAS / "double-gauss-f100-telecentric.toml")}
    tele = cameras["stop at F1U"]       # the same surfaces and b_U, exit pupil at infinity: the paper's model
    rows = []
    for setup, cam in cameras.items():
        a = np.array(GEOMETRY_A[setup])
        y0, mu = slice_rays(cam, a)
        z, y, dz, dy = _optiland_object_rays(cam, y0, mu)
        lens = cam.main_optics.prescription
        z_sensor = lens.rear_principal_plane_mm + cam.main_optics.image_distance_mm + cam.mla_focal_length_mm \
            + cam.mla_principal_plane_gap_mm
        exact = (z_sensor - (z - y / dy * dz)).reshape(y0.shape)[0]        # optiland: where the pair ±c meets
        models = {"paraxial (exit pupil at infinity)": g.slice_distance_mm(tele, a),
                  "exit pupil": g.slice_distance_mm(cam, a), "real rays": g.real_ray_slices(cam, a).distance_mm}
        for model, value in models.items():
            if setup == "stop at F1U" and model == "exit pupil":
                continue                                    # the same numbers as the paraxial row
            rel = np.abs(value - exact) / exact
            rows.append({"setup": setup, "model": model, "a": a.tolist(), "max_rel_error": float(rel.max()),
                         "a_of_max": float(a[int(np.argmax(rel))])})
    zemax = [abs(g.slice_distance_mm(Camera.from_toml(suite.CAMERAS / "paper-f100.toml"), float(a)) - d[1]) / d[1]
             for a, d in suite.TABLE2_ZEMAX.items() if math.isfinite(d[1])]
    n = 10_000 if s.quick else suite.GEOMETRY_SAMPLES
    a_many = np.linspace(0.5, 2.5, n)
    x = np.random.default_rng(0).random(n)
    floor = bl.measure(lambda: x * x + 1.0, s.cheap_repeats, memory=False)
    per_1e6 = 1e6 / n
    speed = {"floor": floor.median_s * per_1e6,
             "paraxial (exit pupil at infinity)": bl.measure(lambda: g.slice_geometry(tele, a_many), s.cheap_repeats,
                                                             memory=False).median_s * per_1e6,
             "exit pupil": bl.measure(lambda: g.slice_geometry(cameras["own stop"], a_many), s.cheap_repeats,
                                      memory=False).median_s * per_1e6}
    few = a_many[:: max(1, n // 10_000)]       # real rays: 1e4 slices, scaled to 1e6
    speed["real rays"] = bl.measure(lambda: g.real_ray_slices(cameras["own stop"], few), s.cheap_repeats,
                                    memory=False).median_s * 1e6 / few.size
    suite.log(f"  geometry: {speed}")
    return {"rows": rows, "paper_zemax_max_rel_error": max(zemax), "seconds_per_1e6_slices": speed,
            "real_rays_timed_slices": int(few.size), "d_a_mm": cameras["own stop"].main_optics.exit_pupil_distance_mm}


# ----------------------------------------------------------------------------- deconvolution
def deconvolution_section(s: suite.Settings) -> dict:
    """``lfproc.deconvolve`` of four wave-rendered beads between voxels and planes (``tests/test_deconvolve.py``)."""
    from test_deconvolve import _camera, _found, _wave_rendered

    import lfproc
    from lfproc.wave import build_operators

    camera, lenses = _camera(), DECONV_LENSES
    lf = lfproc.LightField.from_views(_wave_rendered(camera, lenses, DECONV_BEADS), camera)
    z_um = np.arange(-40.0, 41.0, 10.0)
    rows, build = [], {}
    for superres in DECONV_SUPERRES:
        ops, build[str(superres)] = bl.time_once(lambda: build_operators(camera, list(z_um), superres))
        settings = [(iterations, True) for iterations in DECONV_ITERATIONS] + [(DECONV_ITERATIONS[1], False)]
        for iterations, antialias in settings:
            timing, vol = bl.measure_keeping(lambda: lfproc.deconvolve(lf, z_um=z_um, superres=superres,
                                                                       iterations=iterations, antialias=antialias,
                                                                       operators=ops),
                                             s.repeats, memory=False)
            found = [_found(vol.data, vol.z_um, vol.voxel_um, camera, lenses, superres, bead) for bead in DECONV_BEADS]
            rows.append({"superres": superres, "iterations": iterations, "antialias": antialias,
                         "timing": timing.as_dict(),
                         "voxel_um": list(vol.voxel_um),
                         "worst_lateral_um": max(lateral for _, lateral in found) * vol.voxel_um[1],
                         "on_nearest_plane": sum(z == 10.0 * round(b[2] / 10.0) for (z, _), b in zip(found, DECONV_BEADS)),
                         "worst_z_um": max(abs(z - b[2]) for (z, _), b in zip(found, DECONV_BEADS))})
            suite.log(f"  deconvolve superres {superres}, {iterations} iterations, antialias {antialias}: "
                      f"{timing.median_s:.2f} s, "
                      f"{rows[-1]['worst_lateral_um']:.2f} µm")
    return {"camera": "20x/0.5 water microscope, 125 µm lenses, m̂ = 9", "lenses": list(lenses), "z_um": z_um.tolist(),
            "beads_um": [list(b) for b in DECONV_BEADS], "operators_s": build, "rows": rows}


# ----------------------------------------------------------------------------- the run
def run(quick: bool) -> dict:
    start = time.perf_counter()
    s = suite.settings_for(quick, None)
    machine = bl.machine_info()
    result = {"command": COMMAND + (" --quick" if quick else ""), "quick": quick, "machine": machine,
              "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    suite.log("decode")
    result["decode"], views = decode_section(s)
    suite.log("refocus")
    result["refocus"] = refocus_section(views, s)
    views = None
    suite.log("depth")
    result["depth"] = depth_section(s)
    suite.log("geometry")
    result["geometry"] = geometry_section(s)
    suite.log("deconvolution")
    result["deconvolution"] = deconvolution_section(s)
    machine["load_average_end"] = list(os.getloadavg())
    result["peak_rss_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
    result["total_s"] = time.perf_counter() - start
    return result


# ----------------------------------------------------------------------------- the page
def _t(timing: dict) -> str:
    """Median wall time, fastest, and median CPU time of a :class:`benchlib.Timing` dict."""
    cpu = f", CPU {bl.fmt(timing['cpu_median_s'])}" if timing.get("cpu_median_s") is not None else ""
    return f"{bl.fmt(timing['median_s'])} ({bl.fmt(timing['min_s'])}{cpu})"


def _db(value) -> str:
    return "exact" if value is None else f"{value:.1f}"


def recommendations(r: dict) -> list[str]:
    """Which setting to pick for what, each choice and number taken from the measured results."""
    dec, ref, dep, geo = r["decode"], r["refocus"], r["depth"], r["geometry"]
    speed = {(x["interpolation"], x["demosaic"]): x["timing"]["median_s"] for x in dec["rows"]}
    psnr = {(x["capture"], x["interpolation"], x["demosaic"]): x["psnr_db"] for x in dec["accuracy"]}
    mono = {i: psnr[("mono", i, "fast")] for i in suite.INTERPOLATIONS}
    seen = [i for i in suite.INTERPOLATIONS if mono[i] >= PREVIEW_MIN_DB] or list(suite.INTERPOLATIONS)
    quickest = min(speed[(i, "fast")] for i in seen)
    fastest = max((i for i in seen if speed[(i, "fast")] <= PREVIEW_SLACK * quickest),
                  key=lambda i: mono[i])       # the most accurate of those about as fast as the fastest
    demosaic = sorted(("fast", "careful"), key=lambda d: -psnr[("RGGB", "linear", d)])   # the better one first
    sharpest = max(suite.INTERPOLATIONS, key=lambda i: mono[i])
    real = [x for x in ref["rows"] if x["case"] == "real a" and x["upsample"] == 1]
    best_real = max(real, key=lambda x: x["plane_psnr_db"] or math.inf)
    photo, micro = ref["bias"]["photographic"]["worst_abs_error"], ref["bias"]["microscope"]["worst_abs_error"]
    least_bias = min((x["interpolation"] for x in real), key=lambda i: photo[i])
    least_bias_micro = min((x["interpolation"] for x in real), key=lambda i: micro[i])
    integer = next(x for x in ref["rows"] if x["case"] == "integer a")
    up2 = next(x for x in ref["rows"] if x["upsample"] == 2)
    one_spline = next(x for x in real if x["interpolation"] == "cubic-spline")["timing"]["median_s"]
    many = ref["many_slices"]
    acc = {x["setting"]: x for x in dep["accuracy"]}
    quick_depth = min(dep["speed"], key=lambda x: x["timing"]["median_s"])
    exact_depth = max(dep["accuracy"], key=lambda x: (x["within_dof_every"], -x["median_abs_error_dof"]))
    default_depth = dep["speed"][0]
    own = {x["model"]: x for x in geo["rows"] if x["setup"] == "own stop"}
    tele = {x["model"]: x for x in geo["rows"] if x["setup"] == "stop at F1U"}
    per = geo["seconds_per_1e6_slices"]
    dec_rows = r["deconvolution"]
    placed = [x for x in dec_rows["rows"] if x["on_nearest_plane"] == max(y["on_nearest_plane"] for y in dec_rows["rows"])]
    best_um = min(x["worst_lateral_um"] for x in placed)
    good = [x for x in placed if x["worst_lateral_um"] <= DECONV_SLACK * best_um]
    enough = min(good, key=lambda x: x["timing"]["median_s"])
    filtered = [x for x in good if x["antialias"] and (x["superres"], x["iterations"]) ==
                (enough["superres"], enough["iterations"])]
    enough = filtered[0] if filtered else enough        # the default filter where it places the beads as well
    most = max(dec_rows["rows"], key=lambda x: x["timing"]["median_s"])
    f = bl.fmt
    return [
        "## Which setting to pick", "",
        f"- **Preview**: decode with `{fastest}`, the most accurate of the decodes at or above "
        f"{PREVIEW_MIN_DB:.0f} dB within {(PREVIEW_SLACK - 1) * 100:.0f} % of the fastest of them ({f(speed[(fastest, 'fast')])} s, {mono[fastest]:.1f} dB"
        + (f"; `linear`, the default, {f(speed[('linear', 'fast')])} s and {mono['linear']:.1f} dB" if fastest != "linear"
           else ", the default") + "), refocus at integer a "
        f"(a gather: {f(integer['timing']['median_s'])} s, {f(integer['ratio_to_floor'])} × one read of the views, "
        f"exact), depth with `{quick_depth['setting']}` ({f(quick_depth['timing']['median_s'])} s against "
        f"{f(default_depth['timing']['median_s'])} s for the default; median error "
        f"{f(acc[quick_depth['setting']]['median_abs_error_dof'])} of the DOF against "
        f"{f(acc['default']['median_abs_error_dof'])} on clear lenses, within one DOF on "
        f"{f(acc[quick_depth['setting']]['within_dof_every'] * 100)} % of all lenses against "
        f"{f(acc['default']['within_dof_every'] * 100)} %).",
        f"- **Publication images**: decode with `{sharpest}` (+{mono[sharpest] - mono['linear']:.1f} dB over linear "
        f"for {f(speed[(sharpest, 'fast')] / speed[('linear', 'fast')])} × its time); on a Bayer sensor pick "
        f"the `{demosaic[0]}` demosaic ({psnr[('RGGB', 'linear', demosaic[0])]:.1f} dB, "
        f"{f(speed[('linear', demosaic[0])])} s; `{demosaic[1]}`: "
        f"{psnr[('RGGB', 'linear', demosaic[1])]:.1f} dB, {f(speed[('linear', demosaic[1])])} s). Refocus real a with "
        f"`{best_real['interpolation']}` ({_db(best_real['plane_psnr_db'])} dB on the textured plane, "
        f"{f(best_real['timing']['median_s'])} s a slice); `--upsample 2` where resolution matters "
        f"({f(up2['timing']['median_s'])} s a slice, {_db(up2['plane_psnr_db'])} dB).",
        f"- **Metric measurement**: with the main lens's prescription, real rays "
        f"({f(own['real rays']['max_rel_error'] * 100)} % from optiland's trace of the same rays, "
        f"{f(per['real rays'])} s per 1e6 slices); without it the exit-pupil model "
        f"({f(own['exit pupil']['max_rel_error'] * 100)} % with the lens's own stop, {f(per['exit pupil'])} s per "
        f"1e6 slices). Never the telecentric paraxial model on a lens whose exit pupil is finite: "
        f"{f(own['paraxial (exit pupil at infinity)']['max_rel_error'] * 100)} % off here "
        f"(d_A = {geo['d_a_mm']:.1f} mm); on a telecentric set-up it is "
        f"{f(tele['paraxial (exit pupil at infinity)']['max_rel_error'] * 100)} % off (the paper's Zemax: "
        f"{f(geo['paper_zemax_max_rel_error'] * 100)} %). Real a with `{least_bias}` puts the sharpest slice of a "
        f"sweep within {f(photo[least_bias])} of the true a (linear: {f(photo['linear'])}). Depth with "
        f"`{exact_depth['setting']}`: the most lenses within one DOF of the truth, borders and occlusion edges "
        f"included ({f(exact_depth['within_dof_every'] * 100)} %; median error {f(exact_depth['median_abs_error_dof'])} "
        f"of the DOF on clear lenses).",
        f"- **Many slices**: one call for all of them: {many['count']} real slices take "
        f"{f(many['timing']['median_s'] / many['count'])} s each against {f(one_spline)} s for one slice alone "
        f"({many['interpolation']}).",
        f"- **Microscopes**: refocus with `{least_bias_micro}` (sharpest slice within {f(micro[least_bias_micro])} "
        f"of the true a at m̂ = {ref['bias']['microscope']['m_hat']}; linear {f(micro['linear'])}, nearest "
        f"{f(micro['nearest'])}). Deconvolve with `superres={enough['superres']}`, `iterations={enough['iterations']}`"
        + ("" if enough["antialias"] else ", `antialias=False`")
        + f": the quickest setting that places the beads as well as any here (worst lateral error "
        f"{f(enough['worst_lateral_um'])} µm, {enough['on_nearest_plane']} of {len(dec_rows['beads_um'])} on their nearest "
        f"plane, {f(enough['timing']['median_s'])} s); with the default anti-aliasing filter "
        f"{max(x['on_nearest_plane'] for x in dec_rows['rows'] if x['antialias'])} of {len(dec_rows['beads_um'])} land on "
        f"their nearest plane, without it "
        f"{max(x['on_nearest_plane'] for x in dec_rows['rows'] if not x['antialias'])}. The most work measured, `superres={most['superres']}`, `iterations={most['iterations']}`, "
        f"takes {f(most['timing']['median_s'])} s for {f(most['worst_lateral_um'])} µm. "
        f"The real capture's run: [benchmarks-deconvolution.md](benchmarks-deconvolution.md).", ""]


def markdown(r: dict) -> str:
    """The page ``docs/speed-accuracy.md`` for the results ``r`` (the JSON): every number comes from it."""
    m, dec, ref, dep, geo = r["machine"], r["decode"], r["refocus"], r["depth"], r["geometry"]
    load = ", ".join(f"{v:.2f}" for v in m["load_average_start"])
    load_end = ", ".join(f"{v:.2f}" for v in m["load_average_end"])
    psnr = {(x["capture"], x["interpolation"], x["demosaic"]): x["psnr_db"] for x in dec["accuracy"]}
    bias = ref["bias"]
    out = ["# Speed versus accuracy", "",
           f"Generated by `{r['command']}` on {r['date']} in {r['total_s']:.0f} s ({m['cpu_model']}, "
           f"{m['cpus_usable']} CPUs usable, numpy {m['numpy']}, numba {m['numba']}, OpenCV {m['opencv']}). "
           f"Load average (1, 5, 15 min) at the start {load}, at the end {load_end}: wall times on a loaded "
           f"machine are longer than on an idle one; the CPU time (user + system) beside them and the ratios "
           f"to the floor, measured in the same run, move less. Times: median (fastest, median CPU) of the "
           f"repeats after a warm-up, in seconds. Peak memory of the run {r['peak_rss_gb']:.2f} GB. "
           f"`python scripts/bench_tradeoffs.py --page-only` rewrites this page from "
           f"[speed-accuracy.json](speed-accuracy.json); `tests/test_speed_accuracy.py` checks that they agree.", ""]
    if max(m["load_average_start"][0], m["load_average_end"][0]) > m["cpus_usable"]:
        out += ["**Measured on a busy machine** (load above its CPU count): other work shared the CPUs, so the "
                "wall times here are longer than on an idle machine. The accuracies do not depend on the load; the "
                "choices below that weigh times (the preview's decode and depth, the quickest deconvolution) "
                "may change on an idle one.", ""]
    if r["quick"]:
        out += ["**Quick run** (`--quick`): small captures, one repeat; not the numbers to quote.", ""]
    out += recommendations(r)
    out += ["## Decode", "",
            f"{dec['sensor_shape'][1]} × {dec['sensor_shape'][0]} px {dec['cfa']} capture (simulated, Lytro-Illum-like: "
            f"hexagonal lenses of 14.3 px) to {' × '.join(map(str, dec['views_shape']))} float32 views; the decoder "
            f"(white image's share) built once in {bl.fmt(dec['prepare_s'])} s, the per-capture call timed. Floor: "
            f"one copy of the sensor, {_t(dec['floor'])}. Accuracy: PSNR of views decoded from "
            f"{dec['accuracy_shape'][1]} × {dec['accuracy_shape'][0]} px renders of the paper's f100 camera (9 µm "
            f"pixels, m̂ = 25) against the simulator's ideal views (outer ring of views and border lenses left out).",
            "",
            bl.markdown_table(["interpolation", "demosaic", "time s (fastest, CPU)", "× floor", "PSNR mono dB",
                               "PSNR RGGB dB"],
                              [[x["interpolation"], x["demosaic"], _t(x["timing"]), x["ratio_to_floor"],
                                psnr.get(("mono", x["interpolation"], x["demosaic"])),
                                psnr.get(("RGGB", x["interpolation"], x["demosaic"]))] for x in dec["rows"]]), "",
            "## Refocus", "",
            f"The decoded views above ({ref['gb']:.2f} GB). Floor: one read of the views (`views.sum(axis=(0, 1))`), "
            f"{_t(ref['floor'])}. Plane PSNR: a light field of one textured plane ({ref['plane_lenses'][0]} × "
            f"{ref['plane_lenses'][1]} lenses, two sinusoids below 0.2 cycles per lens) refocused at its own a, "
            f"against the texture. Bias: the sharpest slice (`lfproc.slice_sharpness`) of a sweep in steps "
            f"of 0.001 minus the true a, worst over exact plane views (`lfproc.simulate.plane_views`) at "
            f"{len(bias['photographic']['a0'])} values of a in [{bias['photographic']['a0'][0]:g}, "
            f"{bias['photographic']['a0'][-1]:g}] (photographic, m̂ = {bias['photographic']['m_hat']}) and "
            f"{len(bias['microscope']['a0'])} in [{bias['microscope']['a0'][0]:g}, {bias['microscope']['a0'][-1]:g}] "
            f"(microscope, m̂ = {bias['microscope']['m_hat']}); the sweeps reach ±{bias['half_width']:g} from the true a, so "
            f"{bias['half_width']:g} means at least that far (the sharpest slice snaps to a whole-lens shift); exact "
            f"Fourier shifts: "
            f"{bl.fmt(bias['photographic']['worst_abs_error']['fourier'])} / "
            f"{bl.fmt(bias['microscope']['worst_abs_error']['fourier'])}.", "",
            bl.markdown_table(["case", "interpolation", "upsample", "time s (fastest, CPU)", "× floor",
                               "plane PSNR dB", "bias photographic", "bias microscope"],
                              [[x["case"], x["interpolation"], str(x["upsample"]), _t(x["timing"]), x["ratio_to_floor"],
                                _db(x["plane_psnr_db"]),
                                bias["photographic"]["worst_abs_error"].get(x["interpolation"]) if x["upsample"] == 1 else None,
                                bias["microscope"]["worst_abs_error"].get(x["interpolation"]) if x["upsample"] == 1 else None]
                               for x in ref["rows"]]), "",
            f"{ref['many_slices']['count']} real slices ({ref['many_slices']['interpolation']}) in one call: "
            f"{_t(ref['many_slices']['timing'])}.", "",
            "## Depth", "",
            f"Speed: `lfproc.depth_map` on {' × '.join(map(str, dep['views_shape']))} float32 views (smooth random content "
            f"on two surfaces, `scripts/bench_depth.py`); one cubic refocused slice of them: {_t(dep['one_slice'])}. "
            f"Accuracy: the rendered and decoded scene *{dep['scene']}* (`scripts/bench_depth.py`), textured lenses "
            f"away from borders and occlusions ({dep['accuracy'][0]['lenses']} lenses): |distance error| as a share "
            f"of the slice DOF at the true distance, BadPix (share off by more than one DOF or unknown), coverage "
            f"(share with an estimate); and the share within one DOF on every lens of the textured planes, borders "
            f"and occlusion edges included ({dep['accuracy'][0]['lenses_every']} lenses).", "",
            bl.markdown_table(["setting", "time s (fastest, CPU)", "slices", "view step", "× one slice",
                               "median error / DOF", "BadPix", "coverage", "within one DOF, every lens"],
                              [[sp["setting"], _t(sp["timing"]), str(sp["slices"]), str(sp["view_step"]),
                                sp["ratio_to_one_slice"], ac["median_abs_error_dof"], ac["badpix"], ac["coverage"],
                                ac["within_dof_every"]]
                               for sp, ac in zip(dep["speed"], dep["accuracy"])]), "",
            "## Geometry models", "",
            f"Slice distances d_a of the Double Gauss camera (`samples/cameras/double-gauss-f100.toml`, its own stop: "
            f"exit pupil d_A = {geo['d_a_mm']:.1f} mm; `double-gauss-f100-telecentric.toml`: the stop moved to the "
            f"front focal plane, the paper's set-up), against optiland's exact trace of the same ray pairs "
            f"(independent of lfproc's tracer). *Paraxial*: the paper's model (exit pupil at infinity); *exit pupil*: "
            f"Hahne et al. 2018's; *real rays*: `lfproc.geometry.real_ray_slices`. Time per 1e6 slices (real rays: "
            f"{geo['real_rays_timed_slices']} slices, scaled); floor: one numpy pass over 1e6 values, "
            f"{bl.fmt(geo['seconds_per_1e6_slices']['floor'])} s. The paraxial model against the paper's own Zemax "
            f"trace (Table 2, d_a for a = 1…5): {bl.fmt(geo['paper_zemax_max_rel_error'] * 100)} % at most.", "",
            bl.markdown_table(["set-up", "model", "a", "largest error %", "at a", "s per 1e6 slices"],
                              [[x["setup"], x["model"], ", ".join(f"{a:g}" for a in x["a"]), x["max_rel_error"] * 100,
                                x["a_of_max"], geo["seconds_per_1e6_slices"][x["model"]]] for x in geo["rows"]]), ""]
    dc = r["deconvolution"]
    out += ["## Deconvolution (microscopes)", "",
            f"`lfproc.deconvolve` of {len(dc['beads_um'])} point beads ({dc['camera']}, {dc['lenses'][0]} × "
            f"{dc['lenses'][1]} lenses), rendered through the wave model at their exact positions, 0.3–0.4 voxel and "
            f"up to 2.5 µm off the voxel grid, with Poisson noise (`tests/test_deconvolve.py`), into planes "
            f"{dc['z_um'][0]:g} … {dc['z_um'][-1]:g} µm every {dc['z_um'][1] - dc['z_um'][0]:g} µm; the operators "
            f"(built once per super-resolution: "
            + ", ".join(f"superres {k}: {bl.fmt(v)} s" for k, v in dc["operators_s"].items())
            + ") are not in the times. Accuracy: the brightest voxel near each bead: its lateral distance from the "
            "bead, its plane against the bead's nearest plane, and its plane's distance from the bead's z.", "",
            bl.markdown_table(["superres", "iterations", "anti-aliasing filter", "time s (fastest, CPU)",
                               "lateral voxel µm", "worst lateral error µm", "on the nearest plane", "worst z error µm"],
                              [[str(x["superres"]), str(x["iterations"]), "on (default)" if x["antialias"] else "off",
                                _t(x["timing"]), x["voxel_um"][1],
                                x["worst_lateral_um"], f"{x['on_nearest_plane']} of {len(dc['beads_um'])}",
                                x["worst_z_um"]] for x in dc["rows"]]), ""]
    return "\n".join(out)


def write(result: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "speed-accuracy.json").write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    (out / "speed-accuracy.md").write_text(markdown(result), encoding="utf-8")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small captures, one repeat (about a minute)")
    parser.add_argument("--out", help="folder for speed-accuracy.{md,json} (default docs/; --quick: a temporary one)")
    parser.add_argument("--page-only", action="store_true", help="rewrite the page from the folder's JSON")
    args = parser.parse_args(argv)
    out = Path(args.out) if args.out else (Path(tempfile.mkdtemp(prefix="lfproc-tradeoffs-")) if args.quick else DOCS)
    if args.page_only:
        write(json.loads((out / "speed-accuracy.json").read_text(encoding="utf-8")), out)
    else:
        write(run(args.quick), out)
    print(f"wrote {out / 'speed-accuracy.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
