#!/usr/bin/env python
"""Benchmark of ``lfproc.refocus`` against the memory-speed floor and the usual np.pad shift-and-sum.

Light field: 15 × 15 views of 434 × 625 × 3 float32 (a Lytro Illum decode, 0.73 GB), random data;
``--small`` uses 9 × 9 views of 120 × 160 × 3 for a quick run. Each timing is the median (and the
minimum: the least disturbed run on a shared machine) of ``--repeats`` runs after a warm-up call; the
first call of each kernel (numba compile, or a load from numba's on-disk cache) is reported
separately. Targets (PASS/FAIL):

* one integer slice ≤ 1.5 × the numpy floor ``views.sum(axis=(0, 1))`` (one read of the data);
* ≥ 8 × faster than the baseline of current open-source tools: each view edge-padded with ``np.pad``,
  the shifted window added into a float64 accumulator, divided by the number of views;
* five integer slices in one call ≤ 3.5 × one slice.

Usage: ``python scripts/bench_refocus.py [--small] [--repeats N] [--json PATH]``. The machine may be
shared: rerun when numbers look noisy.
"""

from __future__ import annotations

import argparse
import importlib
import os
import statistics
import sys
import time

import numpy as np

TARGET_FLOOR_RATIO = 1.5
TARGET_BASELINE_SPEEDUP = 8.0
TARGET_FUSED_RATIO = 3.5
INTEGER_A = 2.0
REAL_A = 1.5
FIVE_A = (-2.0, -1.0, 0.0, 1.0, 2.0)


def timings(fn, repeats: int) -> tuple[float, float]:
    """(median, minimum) wall time of ``fn()`` over ``repeats`` runs, after one warm-up run."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def pad_baseline(views: np.ndarray, a: int) -> np.ndarray:
    """What current open-source tools do: edge-pad every view, add the shifted window into float64."""
    m, _, ny, nx, _ = views.shape
    c = (m - 1) // 2
    pad = abs(a) * c
    acc = np.zeros(views.shape[2:], dtype=np.float64)
    for ky in range(m):
        for kx in range(m):
            padded = np.pad(views[ky, kx], ((pad, pad), (pad, pad), (0, 0)), mode="edge")
            sy, sx = pad + a * (c - ky), pad + a * (c - kx)
            acc += padded[sy:sy + ny, sx:sx + nx]
    return (acc / (m * m)).astype(np.float32)


def first_call_seconds(refocus, interpolation: str, a: float) -> float:
    """Time of the first call on a tiny light field: numba compile, or load from the on-disk cache."""
    tiny = np.ones((3, 3, 4, 5, 3), dtype=np.float32)
    start = time.perf_counter()
    refocus(tiny, a, interpolation)
    return time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--small", action="store_true", help="9x9 views of 120x160x3 (quick check)")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs per case (median; default 5)")
    parser.add_argument("--json", metavar="PATH", help="also write the results as JSON")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error("--repeats must be >= 1")

    start = time.perf_counter()
    from lfproc import LightField
    from lfproc.refocus import refocus
    rf = importlib.import_module("lfproc.refocus._refocus")
    import_s = time.perf_counter() - start
    compile_gather_s = first_call_seconds(refocus, "linear", 1.0)
    compile_interp_s = first_call_seconds(refocus, "linear", 0.5)

    shape = (9, 9, 120, 160, 3) if args.small else (15, 15, 434, 625, 3)
    views = np.random.default_rng(1).random(shape, dtype=np.float32)
    lf = LightField.from_views(views)
    gb = views.nbytes / 1e9
    r = args.repeats

    t = {}
    t["numpy floor: views.sum(axis=(0,1))"] = timings(lambda: views.sum(axis=(0, 1)), r)
    t["np.pad baseline, integer a"] = timings(lambda: pad_baseline(views, int(INTEGER_A)), max(1, min(r, 3)))
    t["one integer slice"] = timings(lambda: refocus(lf, INTEGER_A), r)
    for interp in ("nearest", "linear", "cubic"):
        t[f"one real slice, {interp}"] = timings(lambda: refocus(lf, REAL_A, interp), r)
    t["five integer slices, one call"] = timings(lambda: refocus(lf, FIVE_A), r)
    t["five integer slices, separate calls"] = timings(lambda: [refocus(lf, a) for a in FIVE_A], r)
    t["five real slices (linear), one call"] = timings(lambda: refocus(lf, [a + 0.5 for a in FIVE_A]), r)

    def ratio(numerator, denominator, which):
        return t[numerator][which] / t[denominator][which]

    checks = [  # (name, numerator, denominator, op, target)
        ("integer slice / numpy floor", "one integer slice", "numpy floor: views.sum(axis=(0,1))", "<=",
         TARGET_FLOOR_RATIO),
        ("np.pad baseline / integer slice", "np.pad baseline, integer a", "one integer slice", ">=",
         TARGET_BASELINE_SPEEDUP),
        ("five fused / one slice", "five integer slices, one call", "one integer slice", "<=", TARGET_FUSED_RATIO),
    ]
    results = []
    for name, num, den, op, target in checks:
        value, value_min = ratio(num, den, 0), ratio(num, den, 1)
        results.append({"name": name, "value": value, "value_from_minima": value_min, "op": op, "target": target,
                        "pass": bool(value <= target if op == "<=" else value >= target)})

    print(f"light field {shape} float32 = {gb:.3f} GB; threads {rf._thread_count()}, CPUs {os.cpu_count()}; "
          f"median and minimum of {r} runs (baseline: {max(1, min(r, 3))})")
    print(f"import lfproc.refocus {import_s:.2f} s; first call (compile, or load from numba's cache): "
          f"gather {compile_gather_s:.2f} s, interpolated {compile_interp_s:.2f} s")
    print(f"{'case':40s} {'median s':>9s} {'min s':>8s} {'GB/s':>7s}")
    for name, (median, minimum) in t.items():
        print(f"{name:40s} {median:9.4f} {minimum:8.4f} {gb / median:7.2f}")
    print()
    print(f"{'ratio (of medians)':40s} {'value':>7s}  {'target':12s} {'':4s}  of minima")
    for res in results:
        verdict = "PASS" if res["pass"] else "FAIL"
        print(f"{res['name']:40s} {res['value']:7.2f}  {res['op']} {res['target']:<9} {verdict}"
              f"  {res['value_from_minima']:7.2f}")

    if args.json:
        from lfproc.atomic import write_json_atomic
        write_json_atomic(args.json, {
            "shape": list(shape), "gigabytes": gb, "threads": rf._thread_count(), "repeats": r,
            "import_s": import_s, "first_call_gather_s": compile_gather_s,
            "first_call_interpolated_s": compile_interp_s,
            "median_s": {k: v[0] for k, v in t.items()}, "min_s": {k: v[1] for k, v in t.items()},
            "gb_per_s_median": {k: gb / v[0] for k, v in t.items()},
            "checks": results,
        })
    return 0 if all(res["pass"] for res in results) else 1

if __name__ == "__main__":
    sys.exit(main())
