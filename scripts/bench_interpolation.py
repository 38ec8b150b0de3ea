#!/usr/bin/env python
"""Interpolation of refocused slices: speed per slice and the bias of the sharpest slice (issue 21).

For each interpolation (nearest, linear, cubic = Catmull-Rom, cubic-sharp = Keys a = −0.9, cubic-spline =
the cubic spline through each view) and, as the reference without interpolation, exact Fourier shifts:

* **bias**: on exact light fields of textured planes at fractional a (``lfproc.simulate.plane_views``:
  power ∝ 1/f^e, lens integration, aliasing), the sharpest slice of a sweep in steps of 0.001 minus the
  true a — the worst over a0 = 0.02 … 1.98 in steps of 0.04 (photographic, m̂ = 9) and over
  a0 = −0.25 … 0.25 in steps of 0.01 (microscope, m̂ = 15). Two sharpness measures: ``band`` —
  :func:`lfproc.refocusing.slice_sharpness`, the power below a quarter cycle per lens (what lfproc
  recommends) — and ``full`` — the slice's variance, every frequency (aliased detail included).
  ``--exponents`` sets the spectra, ``--coarse`` takes every other a0.
* **speed**: 101 real slices in one call on an Illum-sized light field (15 × 15 views of 434 × 625 × 3
  float32), seconds per slice and as a ratio to the floor of one read of the views
  (``views.sum(axis=(0, 1))``) measured just before it in the same round (median over ``--repeats``
  rounds); one real slice per call; integer slices (a pure gather) for reference.

``--simulator`` adds the same sweep on the photographic simulator's renders of the bundled sample camera.

Usage: ``python scripts/bench_interpolation.py [--repeats N] [--small] [--exponents 2,1.5,3] [--coarse]
[--speed-only] [--bias-only] [--simulator] [--json PATH]``.
Timings on a shared machine: read the ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

INTERPOLATIONS = ("nearest", "linear", "cubic", "cubic-sharp", "cubic-spline")
MEASURES = ("band", "full")


def photographic_a0(coarse=False):
    return np.round(np.arange(0.02, 2.0, 0.08 if coarse else 0.04), 3)


def microscope_a0(coarse=False):
    return np.round(np.arange(-0.25, 0.251, 0.02 if coarse else 0.01), 3)


def sharpness(stack, a, m, measure):
    """``band``: :func:`lfproc.refocusing.slice_sharpness`; ``full``: the variance; inside the border
    that every view reaches."""
    from lfproc.refocusing import slice_sharpness

    border = int(np.ceil(np.abs(a).max() * (m - 1) / 2)) + 3
    if measure == "band":
        return slice_sharpness(stack, border)
    inner = stack[:, border:-border, border:-border, 0]
    return inner.reshape(len(a), -1).var(axis=1)


def sweep_errors(views, a0, half=0.03, step=0.001):
    """{interpolation or "fourier": {measure: sharpest a − a0}} for one light field."""
    import lfproc
    from lfproc.simulate import fourier_refocus

    m = views.shape[0]
    a = np.round(np.arange(a0 - half, a0 + half + step / 2, step), 9)
    out = {}
    for name in INTERPOLATIONS + ("fourier",):
        stack = fourier_refocus(views, a) if name == "fourier" else lfproc.refocus(views, a, interpolation=name)
        out[name] = {mm: float(a[int(np.argmax(sharpness(stack, a, m, mm)))] - a0) for mm in MEASURES}
    return out


def bias_table(exponent, coarse=False):
    """{name: {kind: {measure: (worst |error|, a0 of it)}}} for texture power ∝ 1/f^exponent."""
    from lfproc.simulate import plane_views

    cases = {"photographic": (9, 1, photographic_a0(coarse)), "microscope": (15, 2, microscope_a0(coarse))}
    rows = {name: {} for name in INTERPOLATIONS + ("fourier",)}
    for kind, (m, seed, values) in cases.items():
        errors = [sweep_errors(plane_views(m, 64, a0, seed=seed, exponent=exponent), a0) for a0 in values]
        for name in rows:
            rows[name][kind] = {}
            for mm in MEASURES:
                e = np.abs([err[name][mm] for err in errors])
                rows[name][kind][mm] = (float(e.max()), float(values[int(np.argmax(e))]))
    return rows


def simulator_views(a0, scaled):
    """The photographic simulator's ideal views of the bundled sample camera (11 × 11 views, f/4) of a
    value-noise plane at the distance of slice a0: 2 mm features (``scaled``: 2 mm at the distance of
    a = 0.9, in proportion to the distance elsewhere, the same size in lenses at every a0); views and the
    view mask of the views wholly inside the stop."""
    from dataclasses import replace

    from lfproc import Camera, geometry
    from lfproc.simulate import Noise, Plane, Scene, render_ideal_views

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    camera = replace(Camera.from_toml(os.path.join(root, "lfproc", "samples", "sample", "camera.toml")), cfa="none")
    m = camera.m_hat
    distance = float(geometry.slice_distance_mm(camera, a0))
    feature = 2.0 * distance / float(geometry.slice_distance_mm(camera, 0.9)) if scaled else 2.0
    views, weight, _ = render_ideal_views(camera, Scene([Plane(distance, Noise(feature_mm=feature, seed=3))]),
                                          (11 * 48, 11 * 48), pixel_samples=2, aperture_samples=2, channels=1)
    return views, weight.reshape(m, m, -1).min(axis=2) > 0.999


SIMULATOR_A0 = (0.1, 0.25, 0.4, 0.6, 0.75, 0.9, 1.1, 1.3, 1.5, 1.7, 1.9)


def simulator_bias():
    """{texture: {name: {measure: (worst |sharpest a − a0|, a0 of it)}}} on :func:`simulator_views` (fixed
    and scaled textures), a0 in :data:`SIMULATOR_A0`, sweeps of ±0.05 in steps of 0.001; "fourier": exact
    shifts over the same views."""
    import lfproc
    from lfproc.simulate import fourier_refocus

    result = {}
    for texture in ("fixed 2 mm", "scaled"):
        worst = {name: {mm: (0.0, None) for mm in MEASURES} for name in INTERPOLATIONS[1:] + ("fourier",)}
        for a0 in SIMULATOR_A0:
            views, mask = simulator_views(a0, texture == "scaled")
            lf = lfproc.LightField.from_views(views, view_mask=mask)
            m = views.shape[0]
            a = np.round(np.arange(a0 - 0.05, a0 + 0.0501, 0.001), 9)
            for name in worst:
                stack = (fourier_refocus(views, a, mask) if name == "fourier"
                         else lfproc.refocus(lf, a, interpolation=name))
                for mm in MEASURES:
                    error = abs(float(a[int(np.argmax(sharpness(stack, a, m, mm)))] - a0))
                    if error > worst[name][mm][0] or worst[name][mm][1] is None:
                        worst[name][mm] = (error, a0)
        result[texture] = worst
    return result


def timed(fn):
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def speed_table(repeats, small):
    """Rounds of: the floor, then each interpolation (101 real slices in one call, and one real slice),
    then integer slices; each time divided by the floor of its own round (the load of a shared machine
    drifts between rounds), the median over the rounds reported, and the fastest time."""
    import lfproc

    shape = (9, 9, 120, 160, 3) if small else (15, 15, 434, 625, 3)
    views = np.random.default_rng(0).random(shape, dtype=np.float32)
    real = np.round(np.linspace(-1.5, 1.5, 101) + 0.0037, 9)       # no whole-lens slice among them
    cases = {name: (lambda name=name: lfproc.refocus(views, real, interpolation=name), len(real))
             for name in INTERPOLATIONS}
    cases.update({f"{name}, one slice": (lambda name=name: lfproc.refocus(views, real[50], interpolation=name), 1)
                  for name in INTERPOLATIONS})
    cases["integer a (gather)"] = (lambda: lfproc.refocus(views, np.arange(-5, 6)), 11)
    cases["integer a (gather), one slice"] = (lambda: lfproc.refocus(views, 1.0), 1)
    for fn, _ in cases.values():
        fn()                                                         # compile / load
    floor = lambda: min(timed(lambda: views.sum(axis=(0, 1))) for _ in range(3))
    ratios = {name: [] for name in cases}
    times = {name: [] for name in cases}
    floors = []
    for _ in range(repeats):
        for name, (fn, count) in cases.items():
            f = floor()
            floors.append(f)
            t = timed(fn) / count
            times[name].append(t)
            ratios[name].append(t / f)
    rows = {name: {"s_per_slice": min(times[name]), "over_floor": float(np.median(ratios[name])),
                   "over_floor_range": [float(min(ratios[name])), float(max(ratios[name]))]} for name in cases}
    return {"views": list(shape), "floor_s": min(floors), "rows": rows}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--small", action="store_true")
    parser.add_argument("--exponents", default="2")
    parser.add_argument("--coarse", action="store_true", help="every other a0 in the bias sweeps")
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--speed-only", action="store_true", help="leave out the bias tables")
    parser.add_argument("--bias-only", action="store_true", help="leave out the speed table")
    parser.add_argument("--simulator", action="store_true",
                        help="also the bias on the photographic simulator's renders of the sample camera")
    args = parser.parse_args(argv)
    result = {"bias": {} if args.speed_only else {e: bias_table(float(e), args.coarse)
                                                  for e in args.exponents.split(",")},
              "load_average": os.getloadavg()[0]}
    if args.simulator:
        result["simulator_bias"] = simulator_bias()
        for texture, rows in result["simulator_bias"].items():
            print(f"worst |sharpest a - true a| (at a0) on the simulator's renders (sample camera, value noise, "
                  f"{texture}), measure band / full:")
            for name, row in rows.items():
                print(f"  {name:12s} {row['band'][0]:.3f} ({row['band'][1]:+.2f}) / {row['full'][0]:.3f} "
                      f"({row['full'][1]:+.2f})")
    for exponent, rows in result["bias"].items():
        print(f"worst |sharpest a - true a| (at a0), texture power ~ 1/f^{exponent}, measure band / full:")
        for name, row in rows.items():
            print(f"  {name:12s} " + "   ".join(
                f"{kind} {row[kind]['band'][0]:.3f} ({row[kind]['band'][1]:+.2f}) / {row[kind]['full'][0]:.3f} "
                f"({row[kind]['full'][1]:+.2f})" for kind in ("photographic", "microscope")))
    if not args.bias_only:
        result["speed"] = speed = speed_table(args.repeats, args.small)
        print(f"speed, views {speed['views']}, floor (one read of the views) {1e3 * speed['floor_s']:.1f} ms "
              f"(fastest); per slice, fastest, and x floor of the same round (median, range over rounds):")
        for name, row in speed["rows"].items():
            low, high = row["over_floor_range"]
            print(f"  {name:30s} {1e3 * row['s_per_slice']:7.1f} ms  {row['over_floor']:5.2f}x floor "
                  f"({low:.2f}-{high:.2f})")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
