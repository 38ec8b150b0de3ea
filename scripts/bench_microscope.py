#!/usr/bin/env python
"""Benchmark: a 2048 × 2048 light-field-microscope capture to a 101-slice z-stack, end to end (issue 21).

Capture: the bundled 20x/0.5 camera (lfproc/samples/cameras/lfm-20x.toml, 125 µm lenslets, 6.5 µm pixels
behind a 1.43x relay: 27.5 px per lens, m̂ = 27, about 74 × 74 lenses), rendered by
``lfproc.simulate.render_microscope_sensor`` (beads and a textured sheet), 16-bit TIFF, with its white
image; the grid is calibrated once beforehand (``lfproc calibrate``, not timed: one grid serves every
capture of a session) and the decoder prepared once (timed separately).

Timed per capture, each the best of ``--repeats`` runs after a warm-up (numba compiles on the first):

* read the capture, decode it into views, refocus 101 slices (a = −0.5 … 0.5, ``--interpolation``,
  default cubic-spline as the commands, in one call), write the z-stack (ImageJ hyperstack with µm spacing) — the end-to-end time, target ≤ 3 s;
* the straightforward implementation on the same views: plain numpy shift-and-sum (each view shifted by
  slicing with linear interpolation between whole-lens shifts, summed into a float64 accumulator);
* floors: reading the views once from memory (``views.sum``), and the capture read + decode alone.

CPU time (all threads) is reported beside each wall time: on a loaded machine the wall time is inflated,
the CPU time much less; CPU time / threads estimates the wall time on idle cores.

Threads: ``NUMBA_NUM_THREADS`` (default 2: the issue's 2 cores). Numbers are reported as ratios to the
floor measured in the same run as well as in seconds (a shared machine inflates seconds, not ratios).

Usage: ``python scripts/bench_microscope.py [--repeats N] [--workdir DIR] [--json PATH] [--skip-numpy]
[--interpolation NAME]``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "2")

import numpy as np  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

SENSOR = (2048, 2048)
A_VALUES = np.round(np.linspace(-0.5, 0.5, 101), 9)
TARGET_S = 3.0


CPU = {}


def best_of(fn, repeats, name=None):
    """Fastest wall time of ``repeats`` runs and the last result; the CPU time (all threads) of the fastest
    run goes to ``CPU[name]``."""
    best, result = None, None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        result = fn()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        if best is None or wall < best[0]:
            best = (wall, cpu)
    if name:
        CPU[name] = best[1]
    return best[0], result


def make_inputs(folder, camera):
    """The capture and white image as 16-bit TIFFs, and the grid from lfproc calibrate (once)."""
    from lfproc import geometry
    from lfproc.io import write_image
    from lfproc.simulate import Bead, MicroscopeScene, Sheet, render_microscope_sensor

    capture, white = os.path.join(folder, "capture.tif"), os.path.join(folder, "white.tif")
    if not (os.path.exists(capture) and os.path.exists(white)):
        lat, zpa = camera.main_optics.lateral_sampling_um(camera), geometry.z_per_a_um(camera)
        rng = np.random.default_rng(0)
        beads = tuple(Bead(float(x), float(y), float(z), radius_um=0.6 * lat)
                      for x, y, z in zip(rng.uniform(-30, 30, 12) * lat, rng.uniform(-30, 30, 12) * lat,
                                         rng.uniform(-0.4, 0.4, 12) * zpa))
        scene = MicroscopeScene(beads=beads, sheets=(Sheet(z_um=0.1 * zpa, period_um=4 * lat, low=0.0, high=0.2),))
        image = render_microscope_sensor(camera, scene, SENSOR, pixel_samples=1, aperture_samples=1)
        flat = render_microscope_sensor(camera, None, SENSOR, pixel_samples=2, aperture_samples=1)
        write_image(capture, np.round(60000 * image / image.max()).astype(np.uint16), {}, "tiff")
        write_image(white, np.round(60000 * flat).astype(np.uint16), {}, "tiff")
    grid = os.path.join(folder, "grid.json")
    if not os.path.exists(grid):
        import subprocess
        subprocess.run([sys.executable, "-m", "lfproc", "calibrate", white, "--camera", camera.source, "-o", grid],
                       check=True, env=dict(os.environ, PYTHONPATH=ROOT))
    return capture, white, grid


def numpy_shift_and_sum(views, a_values):
    """The straightforward implementation: per slice and view, a shifted window (linear between the two
    whole-lens shifts), summed; the mean over the views whose samples fall inside."""
    m, _, ny, nx, ch = views.shape
    c = (m - 1) // 2
    out = np.empty((len(a_values), ny, nx, ch), np.float32)
    for i, a in enumerate(a_values):
        acc = np.zeros((ny, nx, ch))
        count = np.zeros((ny, nx, 1))
        for ky in range(m):
            for kx in range(m):
                sy, sx = a * (c - ky), a * (c - kx)
                y0, x0 = int(np.floor(sy)), int(np.floor(sx))
                fy, fx = sy - y0, sx - x0
                # output rows j read j + y0 and j + y0 + 1: keep those inside
                j0, j1 = max(0, -y0), min(ny, ny - y0 - 1)
                i0, i1 = max(0, -x0), min(nx, nx - x0 - 1)
                if j0 >= j1 or i0 >= i1:
                    continue
                v = views[ky, kx]
                top = (1 - fx) * v[j0 + y0:j1 + y0, i0 + x0:i1 + x0] + fx * v[j0 + y0:j1 + y0, i0 + x0 + 1:i1 + x0 + 1]
                bottom = ((1 - fx) * v[j0 + y0 + 1:j1 + y0 + 1, i0 + x0:i1 + x0]
                          + fx * v[j0 + y0 + 1:j1 + y0 + 1, i0 + x0 + 1:i1 + x0 + 1])
                acc[j0:j1, i0:i1] += (1 - fy) * top + fy * bottom
                count[j0:j1, i0:i1] += 1
        out[i] = acc / np.maximum(count, 1)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workdir", default=os.path.join(tempfile.gettempdir(), "lfproc-bench-microscope"))
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--skip-numpy", action="store_true", help="leave out the (slow) plain numpy baseline")
    parser.add_argument("--interpolation", default="cubic-spline", help="of the z-stack (default: the commands')")
    args = parser.parse_args(argv)
    os.makedirs(args.workdir, exist_ok=True)

    from lfproc import Camera, refocus
    from lfproc.outputs import lateral_um_per_lens, slice_metadata, write_focal_stack
    from lfproc.api import prepare_decoding

    camera = Camera.from_toml(os.path.join(ROOT, "lfproc", "samples", "cameras", "lfm-20x.toml"))
    capture, white, grid = make_inputs(args.workdir, camera)
    t0 = time.perf_counter()
    setup = prepare_decoding(camera, white=white, grid=grid, cache=True)
    lf = setup.decode(capture)               # builds the decoder (once per session)
    setup_s = time.perf_counter() - t0
    records = slice_metadata(capture, camera, A_VALUES)
    stack_path = os.path.join(args.workdir, "capture_stack.tif")

    def end_to_end():
        field = setup.decode(capture)
        stack = refocus(field, A_VALUES, interpolation=args.interpolation)
        write_focal_stack(stack_path, stack, records, kind="imagej", lens_um=lateral_um_per_lens(camera))
        return field

    refocus(lf, A_VALUES[:2], interpolation=args.interpolation)          # compile / load the kernels
    total_s, lf = best_of(end_to_end, args.repeats, "end_to_end")
    decode_s, _ = best_of(lambda: setup.decode(capture), args.repeats, "read_and_decode")
    refocus_s, stack = best_of(lambda: refocus(lf, A_VALUES, interpolation=args.interpolation), args.repeats,
                               "refocus")
    linear_s, _ = best_of(lambda: refocus(lf, A_VALUES, interpolation="linear"), args.repeats, "refocus_linear")
    nearest_s, _ = best_of(lambda: refocus(lf, A_VALUES, interpolation="nearest"), args.repeats, "refocus_nearest")
    write_s, _ = best_of(lambda: write_focal_stack(stack_path, stack, records, kind="imagej",
                                                   lens_um=lateral_um_per_lens(camera)), args.repeats, "write")
    views = np.ascontiguousarray(lf.views)
    floor_s, _ = best_of(lambda: views.sum(axis=(0, 1)), max(args.repeats, 5), "floor")
    result = dict(interpolation=args.interpolation, sensor=list(SENSOR), m_hat=camera.m_hat, lenses=list(lf.lens_shape), slices=len(A_VALUES),
                  threads=int(os.environ["NUMBA_NUM_THREADS"]), decoder_setup_s=setup_s, end_to_end_s=total_s,
                  read_and_decode_s=decode_s, refocus_101_s=refocus_s, refocus_101_linear_s=linear_s,
                  refocus_101_nearest_s=nearest_s, write_stack_s=write_s, views_read_floor_s=floor_s,
                  target_s=TARGET_S, cpu_s=dict(CPU), load_average=os.getloadavg()[0],
                  refocus_over_floor=refocus_s / floor_s, refocus_per_slice_over_floor=refocus_s / len(A_VALUES) / floor_s)
    if not args.skip_numpy:
        numpy_s, reference = best_of(lambda: numpy_shift_and_sum(views, A_VALUES), 1, "numpy_shift_and_sum")
        linear_stack = refocus(lf.views, A_VALUES, interpolation="linear")
        # the baseline leaves out samples on the array's last row/column (it reads two taps): compare inside
        inner = (slice(None), slice(14, -14), slice(14, -14))
        scale = float(np.abs(linear_stack).max())
        result.update(numpy_shift_and_sum_s=numpy_s, cpu_s=dict(CPU),
                      speedup_over_numpy_wall=numpy_s / linear_s,
                      speedup_over_numpy_cpu=CPU["numpy_shift_and_sum"] / CPU["refocus_linear"],
                      numpy_matches_linear=bool(np.allclose(reference[inner], linear_stack[inner],
                                                            atol=1e-5 * scale, rtol=0)))
    print(json.dumps(result, indent=1))
    idle = CPU["end_to_end"] / result["threads"]
    print(f"end to end {total_s:.2f} s wall (target {TARGET_S} s: {'PASS' if total_s <= TARGET_S else 'FAIL'}), "
          f"{CPU['end_to_end']:.2f} s of CPU = {idle:.2f} s on {result['threads']} idle cores if the work splits "
          f"evenly (load average {result['load_average']:.1f}); refocus of 101 slices "
          f"{refocus_s / floor_s:.0f}x one read of the views")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump(result, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
