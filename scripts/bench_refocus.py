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
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402  (this folder)
import benchsim as suite  # noqa: E402

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
    from lfproc.refocusing import refocus
    rf = importlib.import_module("lfproc.refocusing._refocus")
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
    print(f"import lfproc.refocusing {import_s:.2f} s; first call (compile, or load from numba's cache): "
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


# ----------------------------------------------------------------------------- the stage of scripts/bench.py
def first_refocus_calls() -> dict:
    """First calls in this process on a tiny light field: numba compile or load from its on-disk cache."""
    from lfproc.refocusing import refocus

    tiny = np.ones((3, 3, 4, 5, 3), dtype=np.float32)
    _, gather = bl.time_once(lambda: refocus(tiny, 1.0))
    _, interp = bl.time_once(lambda: refocus(tiny, 0.5))
    return {"first_call_gather_s": gather, "first_call_interpolated_s": interp}


def fresh_compile_seconds() -> dict:
    """The same first calls in a subprocess whose numba cache is empty: the compile time of a fresh install."""
    code = ("import time, numpy as np\n"
            "t = time.perf_counter(); from lfproc.refocusing import refocus; imp = time.perf_counter() - t\n"
            "v = np.ones((3, 3, 4, 5, 3), np.float32)\n"
            "t = time.perf_counter(); refocus(v, 1.0); g = time.perf_counter() - t\n"
            "t = time.perf_counter(); refocus(v, 0.5); i = time.perf_counter() - t\n"
            "print(imp, g, i)\n")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                             cwd=str(suite.ROOT))
    imp, gather, interp = (float(v) for v in out.stdout.split())
    return {"import_s": imp, "compile_gather_s": gather, "compile_interpolated_s": interp}


def stage_refocus(views: np.ndarray, s: suite.Settings, first_calls: dict) -> dict:
    """Refocus timings on the decoded light field, accuracy on a crop and on an analytic plane."""
    from lfproc.refocusing import refocus

    gb = views.nbytes / 1e9
    floor = bl.measure(lambda: views.sum(axis=(0, 1)), s.cheap_repeats)
    cases = [("integer a", suite.INTEGER_A, "linear", 1), ("integer a", suite.INTEGER_A, "linear", 2)]
    cases += [("real a", suite.REAL_A, interp, up) for up in (1, 2) for interp in suite.REFOCUS_INTERPOLATIONS]
    ny, nx = s.refocus_accuracy_lenses
    y0, x0 = (views.shape[2] - ny) // 2, (views.shape[3] - nx) // 2
    crop = np.ascontiguousarray(views[:, :, y0:y0 + ny, x0:x0 + nx])
    plane, texture = bl.plane_light_field(views.shape[0], (ny, nx), suite.REAL_A)
    rows = []
    for label, a, interp, up in cases:
        timing = bl.measure(lambda: refocus(views, a, interp, up), s.cheap_repeats)
        reference = bl.refocus_reference(crop, a, interp, up)
        got = refocus(crop, a, interp, up)
        scale = float(np.max(np.abs(reference)))
        row = {"case": label, "a": a, "interpolation": interp if (a != int(a) or up > 1) else "(gather)",
               "upsample": up, "timing": timing.as_dict(), "gb_per_s": gb / timing.median_s,
               "ratio_to_floor": timing.median_s / floor.median_s,
               "max_rel_error_vs_float64": float(np.max(np.abs(got - reference))) / scale,
               "psnr_vs_float64_db": bl.psnr_db(got, reference)}
        if label == "real a":
            out = refocus(plane, a, interp, up)
            py = np.arange(out.shape[0]) / up
            px = np.arange(out.shape[1]) / up
            truth = texture(py[:, None], px[None, :])
            border = 2 * up   # cubic taps clamp at the array edge; compare the interior
            row["plane_psnr_db"] = bl.psnr_db(out[border:-border, border:-border, 0],
                                              truth[border:-border, border:-border], peak=1.0)
        rows.append(row)
        suite.log(f"  refocus {label} {interp} x{up}: {timing.median_s:.3f} s, {row['ratio_to_floor']:.2f} x floor")
    scaling = {"slices": list(suite.SLICE_COUNTS), "integer_s": [], "real_linear_s": []}
    for k in suite.SLICE_COUNTS:
        integer = [float((i % 5) - 2) for i in range(k)]        # cycles through −2 … 2
        real = [float(v) for v in np.linspace(-2.0, 2.0, k) + 0.37]   # fractional positions
        scaling["integer_s"].append(bl.measure(lambda: refocus(views, integer), s.cheap_repeats, memory=False).median_s)
        scaling["real_linear_s"].append(bl.measure(lambda: refocus(views, real), s.cheap_repeats, memory=False).median_s)
        suite.log(f"  refocus {k} slices: {scaling['integer_s'][-1]:.3f} s integer, {scaling['real_linear_s'][-1]:.3f} s real")
    scaling["integer_fit"] = bl.power_law_fit(suite.SLICE_COUNTS, scaling["integer_s"])
    scaling["real_linear_fit"] = bl.power_law_fit(suite.SLICE_COUNTS, scaling["real_linear_s"])
    return {"views_shape": list(views.shape), "gb": gb, "floor": floor.as_dict(),
            "floor_gb_per_s": gb / floor.median_s, "rows": rows, "scaling": scaling,
            "accuracy_crop_lenses": [ny, nx], "compile": first_calls}


def suite_section(r: dict) -> list[str]:
    """The refocus section of docs/benchmarks.md (``scripts/bench.py``)."""
    out = []
    rf = r["refocus"]
    comp_r = rf["compile"]
    out += ["## Refocus (`lfproc.refocus`)", "",
            f"Light field: the decoded views above, {' × '.join(str(v) for v in rf['views_shape'])} float32 "
            f"({rf['gb']:.2f} GB). Floor: `views.sum(axis=(0, 1))`, {bl.fmt(rf['floor']['median_s'])} s "
            f"({rf['floor_gb_per_s']:.1f} GB/s), one read of the data. Integer a = {suite.INTEGER_A:g}, real a = "
            f"{suite.REAL_A}. Accuracy: (1) against a plain float64 numpy implementation of the contract's formula "
            f"(`benchlib.refocus_reference`) on a {rf['accuracy_crop_lenses'][0]} × {rf['accuracy_crop_lenses'][1]}-lens "
            f"crop: the float32 arithmetic's error; (2) *plane PSNR*: a light field of one textured plane at "
            f"disparity a = {suite.REAL_A} (two sinusoids below 0.2 cycles per lens) refocused at that a against the "
            f"texture itself: the interpolation's error.", "",
            bl.markdown_table(["case", "interpolation", "upsample", "time s (min)", "GB/s", "× floor", "peak MB",
                               "max rel. err vs float64", "plane PSNR dB"],
                              [[x["case"], x["interpolation"], str(x["upsample"]), bl.fmt_timing(x["timing"]), x["gb_per_s"],
                                x["ratio_to_floor"], bl.fmt_peak(x["timing"]), x["max_rel_error_vs_float64"],
                                x.get("plane_psnr_db")] for x in rf["rows"]]), "",
            f"Compilation (excluded above): first call in this process (numba's on-disk cache present) "
            f"{bl.fmt(comp_r['first_call_gather_s'])} s gather, {bl.fmt(comp_r['first_call_interpolated_s'])} s "
            f"interpolated"
            + (f"; in a fresh process with an empty cache (a fresh install) {bl.fmt(comp_r['compile_gather_s'])} s "
               f"and {bl.fmt(comp_r['compile_interpolated_s'])} s, after {bl.fmt(comp_r['import_s'])} s to import"
               if "compile_gather_s" in comp_r else "") + ".", "",
            "### Refocus time against slices per call", "",
            "Integer slices cycle through a = −2 … 2; real slices are spread evenly over [−1.63, 2.37] (linear interpolation).",
            "",
            bl.markdown_table(["slices K", "integer s", "× floor", "real (linear) s", "× floor"],
                              [[str(k), ti, ti / rf["floor"]["median_s"], tr, tr / rf["floor"]["median_s"]]
                               for k, ti, tr in zip(rf["scaling"]["slices"], rf["scaling"]["integer_s"],
                                                    rf["scaling"]["real_linear_s"])]), "",
            f"Fits: integer time ∝ K^{rf['scaling']['integer_fit']['exponent']:.2f} (R² = "
            f"{rf['scaling']['integer_fit']['r2']:.3f}); real time ∝ K^{rf['scaling']['real_linear_fit']['exponent']:.2f} "
            f"(R² = {rf['scaling']['real_linear_fit']['r2']:.3f}).", ""]
    return out


if __name__ == "__main__":
    sys.exit(main())
