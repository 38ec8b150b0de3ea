#!/usr/bin/env python
"""Interpolation of refocused slices: speed per slice and the bias of the sharpest slice (issue 21).

For each interpolation (nearest, linear, cubic = Catmull-Rom, cubic-sharp = Keys a = −0.9):

* **bias**: on exact light fields of textured planes at fractional a (``lfproc.simulate.plane_views``:
  natural-image statistics, lens integration, aliasing), the sharpest slice of a sweep in steps of
  0.001 (sharpness: the slice's variance inside the border) minus the true a — the worst over the
  fractional parts 0.1, 0.25, 0.5, 0.75, 0.9 near 0 and near 1 (photographic, m̂ = 9) and over
  a = −0.05 … 0.2 (microscope, m̂ = 15). ``--exponents`` repeats it for other texture spectra.
* **speed**: 101 real slices in one call on an Illum-sized light field (15 × 15 views of 434 × 625 × 3
  float32), seconds per slice and as a ratio to the floor of one read of the views
  (``views.sum(axis=(0, 1))``), measured in the same run; integer slices (a pure gather) for reference.

``--simulator`` adds the same sweep on the photographic simulator's renders of the bundled sample camera.

Usage: ``python scripts/bench_interpolation.py [--repeats N] [--small] [--exponents 2,1.5,3] [--speed-only]
[--simulator]``.
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
PHOTOGRAPHIC = (0.1, 0.25, 0.5, 0.75, 0.9, 1.1, 1.25, 1.5, 1.75, 1.9)
MICROSCOPE = (-0.05, 0.01, 0.025, 0.05, 0.1, 0.2)


def sharpest_error(views, a0, interpolation, half=0.1, step=0.001):
    import lfproc

    m = views.shape[0]
    a = np.round(np.arange(a0 - half, a0 + half + step / 2, step), 9)
    stack = lfproc.refocus(views, a, interpolation=interpolation)
    border = int(np.ceil(np.abs(a).max() * (m - 1) / 2)) + 3
    inner = stack[:, border:-border, border:-border, 0].reshape(len(a), -1)
    return float(a[int(np.argmax(inner.var(axis=1)))] - a0)


def bias_table(exponent):
    from lfproc.simulate import plane_views

    rows = {}
    cases = {"photographic": (9, 1, PHOTOGRAPHIC), "microscope": (15, 2, MICROSCOPE)}
    fields = {kind: [plane_views(m, 64, a0, seed=seed, exponent=exponent) for a0 in values]
              for kind, (m, seed, values) in cases.items()}
    for interpolation in INTERPOLATIONS:
        rows[interpolation] = {kind: max(abs(sharpest_error(v, a0, interpolation))
                                         for v, a0 in zip(fields[kind], cases[kind][2])) for kind in cases}
    return rows


def simulator_bias(feature_mm=2.0):
    """The same sweep on the photographic simulator's ideal views of the bundled sample camera (11 × 11
    views, f/4; only the views wholly inside the stop are averaged) of a value-noise plane at the
    distance of each a0: worst |error| per interpolation."""
    from dataclasses import replace

    import lfproc
    from lfproc import Camera, geometry
    from lfproc.simulate import Noise, Plane, Scene, render_ideal_views

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    camera = replace(Camera.from_toml(os.path.join(root, "lfproc", "samples", "sample", "camera.toml")), cfa="none")
    m = camera.m_hat
    worst = {name: 0.0 for name in INTERPOLATIONS[1:]}
    for a0 in (0.1, 0.25, 0.5, 0.75, 0.9, 1.1, 1.5, 1.9):
        scene = Scene([Plane(float(geometry.slice_distance_mm(camera, a0)), Noise(feature_mm=feature_mm, seed=3))])
        views, weight, _ = render_ideal_views(camera, scene, (11 * 48, 11 * 48), pixel_samples=2, aperture_samples=2,
                                              channels=1)
        lf = lfproc.LightField.from_views(views, view_mask=weight.reshape(m, m, -1).min(axis=2) > 0.999)
        a = np.round(np.arange(a0 - 0.05, a0 + 0.0501, 0.001), 9)
        border = int(np.ceil(np.abs(a).max() * (m - 1) / 2)) + 3
        for name in worst:
            stack = lfproc.refocus(lf, a, interpolation=name)
            found = a[int(np.argmax(stack[:, border:-border, border:-border, 0].reshape(len(a), -1).var(axis=1)))]
            worst[name] = max(worst[name], abs(float(found - a0)))
    return worst


def best_of(fn, repeats):
    best = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best or 1e99, time.perf_counter() - t0)
    return best


def speed_table(repeats, small):
    import lfproc

    shape = (9, 9, 120, 160, 3) if small else (15, 15, 434, 625, 3)
    views = np.random.default_rng(0).random(shape, dtype=np.float32)
    real = np.round(np.linspace(-1.5, 1.5, 101) + 0.0037, 9)       # no whole-lens slice among them
    floor = best_of(lambda: views.sum(axis=(0, 1)), max(repeats, 5))
    rows = {}
    for interpolation in INTERPOLATIONS:
        lfproc.refocus(views, real[:2], interpolation=interpolation)          # compile / load
        per_slice = best_of(lambda: lfproc.refocus(views, real, interpolation=interpolation), repeats) / len(real)
        rows[interpolation] = {"s_per_slice": per_slice, "over_floor": per_slice / floor}
    gather = best_of(lambda: lfproc.refocus(views, np.arange(-5, 6)), repeats) / 11
    rows["integer a (gather)"] = {"s_per_slice": gather, "over_floor": gather / floor}
    return {"views": list(shape), "floor_s": floor, "rows": rows}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--small", action="store_true")
    parser.add_argument("--exponents", default="2")
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--speed-only", action="store_true", help="leave out the bias tables")
    parser.add_argument("--simulator", action="store_true",
                        help="also the bias on the photographic simulator's renders of the sample camera")
    args = parser.parse_args(argv)
    result = {"bias": {} if args.speed_only else {e: bias_table(float(e)) for e in args.exponents.split(",")},
              "speed": speed_table(args.repeats, args.small), "load_average": os.getloadavg()[0]}
    if args.simulator:
        result["simulator_bias"] = simulator_bias()
        print("worst |sharpest a - true a| on the simulator's renders (sample camera, value noise):",
              ", ".join(f"{k} {v:.3f}" for k, v in result["simulator_bias"].items()))
    for exponent, rows in result["bias"].items():
        print(f"worst |sharpest a - true a|, texture power ~ 1/f^{exponent}:")
        for name, row in rows.items():
            print(f"  {name:12s} photographic {row['photographic']:.3f}   microscope {row['microscope']:.3f}")
    speed = result["speed"]
    print(f"speed, views {speed['views']}, floor (one read of the views) {1e3 * speed['floor_s']:.1f} ms:")
    for name, row in speed["rows"].items():
        print(f"  {name:18s} {1e3 * row['s_per_slice']:7.1f} ms per slice  {row['over_floor']:5.2f}x floor")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
