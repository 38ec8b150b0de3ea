#!/usr/bin/env python
"""Benchmark every pipeline stage for speed, memory and accuracy; write ``docs/benchmarks.{md,json,png}``.

Captures are simulated (``lfproc.simulate.render``), so every accuracy has an exact reference:

* **read** — ``lfproc.io.read_capture`` of a 16-bit PNG and an uncompressed TIFF of a Lytro-Illum-sized
  raw (7728 × 5368 px); floors: OpenImageIO's native 16-bit read of the same file, ``numpy.fromfile``.
  Accuracy: against ``(DN − black)/(white − black)`` in float64.
* **calibrate** — ``lfproc.calibrate.estimate_grid`` on white images of several sizes; accuracy: RMS
  distance of the true lens centres from the fitted lattice, pitch and rotation errors.
* **decode** — ``make_decoder`` + call on the Lytro-sized raw for each interpolation (nearest, linear,
  cubic, lanczos) and demosaic (fast, careful); floors: ``cv2.remap`` alone with the same maps, a numpy
  copy of the sensor. Accuracy: PSNR of decoded views against the simulator's ideal views on smaller
  captures rendered with fine quadrature (outer ring of views and border lenses excluded: crosstalk).
* **refocus** — integer ``a`` and real ``a`` with each interpolation and upsampling 1 and 2 on the
  decoded Lytro light field; floor: ``views.sum(axis=(0, 1))``. Accuracy: against a float64 numpy
  implementation of the contract's formula, and against the analytic in-focus texture of a plane.
* **views** — ``viewpoints`` (with and without the aperture mask) and the mosaic; floor: a copy.
* **geometry** — ``slice_geometry`` on 10⁶ values of ``a``; accuracy against the paper's Tables 2 and 4,
  the paraxial model against the paper's Zemax simulation, and the thin-lens against the thick-lens model.
* **scaling** — decode time against sensor size and refocus time against slices per call, with fitted
  power-law exponents.

Timing: the median (and minimum) of ``--repeats`` runs after an untimed warm-up; numba compilation is
excluded and reported separately. Peak memory: the tracemalloc peak of the warm-up call (numpy and
OpenCV outputs, which are numpy arrays; not numba's internal buffers). The machine may be shared: the
load average at start and end is recorded.

Each stage's code (measurement and its section of the page) lives in its own script, which also
runs alone: ``bench_read.py``, ``bench_calibrate.py``, ``bench_decode.py``, ``bench_refocus.py``,
``bench_views.py``, ``bench_geometry.py``; the cameras, captures and settings they share are in
``benchsim.py``, the timing and table helpers in ``benchlib.py``. This script runs them in order on one
rendered capture, adds the machine description and the interpretation, and writes the page.

Usage: ``python scripts/bench.py [--quick] [--repeats N] [--out-dir DIR]``. The full run takes about
8 minutes on 2 cores and writes to ``docs/``; ``--quick`` is a ~1 minute smoke run on smaller captures
that writes to a temporary folder unless ``--out-dir`` is given.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_calibrate  # noqa: E402  (the script's own folder)
import bench_decode  # noqa: E402
import bench_geometry  # noqa: E402
import bench_read  # noqa: E402
import bench_refocus  # noqa: E402
import bench_views  # noqa: E402
import benchlib as bl  # noqa: E402
import benchsim as suite  # noqa: E402

ROOT = suite.ROOT
#: the stages in the order run and shown: (results key, script)
STAGES = (("read", bench_read), ("calibrate", bench_calibrate), ("decode", bench_decode), ("refocus", bench_refocus),
          ("views", bench_views), ("geometry", bench_geometry))


# ============================================================================ driver
def run(s: suite.Settings) -> dict:
    """Every stage on one rendered capture (the stages' own functions), with the machine and timings."""
    start = time.perf_counter()
    machine = bl.machine_info()
    results = {"settings": dataclasses.asdict(s), "machine": machine}
    stage_s = results["stage_seconds"] = {}
    first_calls = bench_refocus.first_refocus_calls()   # before anything else touches the numba kernels
    if s.fresh_compile:
        suite.log("numba compile time in a fresh process")
        first_calls.update(bench_refocus.fresh_compile_seconds())
    big = suite.big_capture(s)
    camera = big["camera"]
    results["camera"] = {"description": suite.camera_description(camera, s.big_shape), "render_s": big["render_s"],
                         "toml": camera.to_toml()}

    def stage(name, fn):
        suite.log(name)
        value, stage_s[name] = bl.time_once(fn)
        return value

    with tempfile.TemporaryDirectory() as tmp:
        results["read"] = stage("read", lambda: bench_read.stage_read(big["sim"].raw, camera, s, tmp))
    results["calibrate"] = stage("calibrate", lambda: bench_calibrate.stage_calibrate(big["white"], camera, s))
    results["decode"], views = stage("decode", lambda: bench_decode.stage_decode_speed(
        big["raw"], big["white"], big["sim"].grid, camera, s))
    full_row = next(x for x in results["decode"]["rows"] if x["interpolation"] == "linear" and x["demosaic"] == "fast")
    results["decode_scaling"] = stage("decode_scaling", lambda: bench_decode.stage_decode_scaling(
        big["raw"], big["white"], camera, s, full_row))
    big = None   # free the sensor images before the accuracy renders
    results["decode_accuracy"] = stage("decode_accuracy", lambda: bench_decode.stage_decode_accuracy(s))
    results["refocus"] = stage("refocus", lambda: bench_refocus.stage_refocus(views, s, first_calls))
    results["views"] = stage("views", lambda: bench_views.stage_views(views, camera, s))
    results["geometry"] = stage("geometry", lambda: bench_geometry.stage_geometry(s))
    machine["load_average_end"] = list(os.getloadavg())
    results["peak_rss_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6   # kB on Linux
    results["total_s"] = time.perf_counter() - start
    return results


# ============================================================================ report
#: the stages measured by their own scripts (each page says how it was made); listed at the top of this page
STAGE_PAGES = [
    "Stages with their own benchmark script and page: [calibration](benchmarks-calibrate.md) "
    "(`scripts/bench_calibrate.py`), [decoding: bias, colour, memory](benchmarks-decode.md) "
    "(`scripts/bench_decode.py`), [Lytro unpacking](benchmarks-lytro.md) (`scripts/bench_lytro.py`), "
    "[geometry and triangulation](benchmarks-geometry.md) (`scripts/bench_geometry.py`), "
    "[depth maps](benchmarks-depth.md) (`scripts/bench_depth.py`), [the viewer](benchmarks-viewer.md) "
    "(`scripts/bench_viewer.py`), [whole commands: time, peak memory, view writing against the disk]"
    "(benchmarks-commands.md) (`scripts/bench_commands.py`), [refocusing](benchmarks-refocus.md) "
    "(`scripts/bench_refocus.py`), [speed versus accuracy, which setting for what](speed-accuracy.md) "
    "(`scripts/bench_tradeoffs.py`). The tables below (`scripts/bench.py`) predate this wave's calibration "
    "and decoding changes where those pages give newer numbers. Their headline numbers (Illum-sized "
    "inputs, 2 cores, 2026-11-23; each page has the method, the load and the floor of its run):",
    "",
    "| stage | measured | floor or baseline in the same run | target |",
    "| --- | --- | --- | --- |",
    "| unpack a 7728 × 5368 10-bit Illum raw | 0.28 s | `numpy.fromfile` of the bytes 0.048 s; straightforward "
    "numpy 2.4 s | ≤ 0.5 s |",
    "| `lfproc calibrate`, 41 Mpx white | 2.6 s CPU, 0.34 GB peak | one FFT of the image 0.84 s CPU; previous code "
    "40 s, 2.96 GB | ≤ 3 s, ≤ 1.5 GB |",
    "| `lfproc refocus` / `views`, whole command, saved calibration | 3.9 / 3.2 s CPU, 0.89 / 0.83 GB peak | the "
    "code before the decoder cache, same run: 8.0 / 7.7 s CPU, 2.08 / 2.02 GB | ≤ 5 s, ≤ 1.5 GB |",
    "| writing 225 view TIFFs + sidecars | 58–98 % of the disk's sequential speed (two runs, fastest of 3 each) | one `tofile` of the same bytes | "
    "≥ 50 % |",
    "| depth map of a 15 × 15 × 434 × 625 × 3 light field | 1.7 s | 28 × one refocused slice | ≤ 10 s |",
    "| viewer page of the same light field | 2.8 s | straightforward version 33.9 s | ≤ 15 s |",
    "| geometry with exit pupil, triangulation | 4e6–2.3e7 evaluations/s | — | ≥ 1e6/s |",
]


def render_markdown(r: dict) -> str:
    m, s = r["machine"], r["settings"]
    out = ["# Benchmarks", "", STAGE_PAGES[0], "", *STAGE_PAGES[2:], ""]
    if s["quick"]:
        out += ["> **Quick smoke run** (`--quick`): small captures, few repeats. Not for publication.", ""]
    out += [f"Generated by `python scripts/bench.py{' --quick' if s['quick'] else ''}` on {m['date']} "
            f"in {r['total_s'] / 60:.1f} min. Regenerate with the same command; numbers move with the machine and "
            f"its load.", "",
            "| machine | |", "| --- | --- |",
            f"| CPU | {m['cpu_model']} — {m['cpu_count']} logical CPUs ({m['cpus_usable']} usable), "
            f"{bl.fmt(m['memory_gb'])} GB RAM |",
            f"| load average (1, 5, 15 min) | start {', '.join(f'{v:.2f}' for v in m['load_average_start'])}; "
            f"end {', '.join(f'{v:.2f}' for v in m['load_average_end'])} |",
            f"| threads | numba {m['numba_threads']}, OpenCV {m['opencv_threads']} |",
            f"| versions | Python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, OpenCV {m['opencv']}, "
            f"OpenImageIO {m['openimageio']}, SciPy {m['scipy']} |",
            f"| platform | {m['platform']} |",
            f"| peak RSS of the whole run | {r['peak_rss_gb']:.1f} GB |", "",
            "**Method.** Time = median of "
            f"{s['repeats']} timed runs (decoding the big capture, calibration) or {s['cheap_repeats']} (everything "
            "else) after one untimed warm-up (minimum in brackets: the least disturbed run on a "
            "shared machine). *× floor* = median time / the floor's median time, both measured in this run. "
            "Peak memory = tracemalloc peak of new allocations during the warm-up call, in MB: numpy arrays, "
            "including OpenCV's outputs; numba's internal buffers are not traced. Throughput counts the stage's "
            "input (sensor megapixels, or gigabytes of views).", ""]
    cam = r["camera"]
    out += ["**Captures.** " + cam["description"], "",
            f"Wall time of this run: rendering the capture {cam['render_s']:.0f} s; "
            + ", ".join(f"{k.replace('_', ' ')} {v:.0f} s" for k, v in r["stage_seconds"].items()) + ".", ""]
    for _, script in STAGES:
        out += script.suite_section(r)
    out += ["## Cost against size and slices", "", "![scaling](benchmarks.png)", "",
            "## Interpretation", ""] + [f"- {line}" for line in interpretation(r)] + [""]
    return "\n".join(out)


def _growth(exponent: float) -> str:
    if exponent < 0.9:
        return "sub-linear (fixed costs still matter at the small sizes)"
    if exponent <= 1.15:
        return "linear in the number of pixels, as one resampling pass should be"
    return "slightly super-linear (cache effects on the larger arrays, or machine noise)"


def _span(values, unit: str, decimals: int = 1) -> str:
    """``"a–b unit"``, or ``"a unit"`` when all values agree at that precision."""
    low, high = f"{min(values):.{decimals}f}", f"{max(values):.{decimals}f}"
    return f"{low} {unit}" if low == high else f"{low}–{high} {unit}"


def interpretation(r: dict) -> list[str]:
    """Short findings, worded from the numbers of this run."""
    dec, acc, rf = r["decode"], r["decode_accuracy"], r["refocus"]
    by = {(x["interpolation"], x["demosaic"]): x for x in dec["rows"]}
    psnr = {(x["capture"], x["interpolation"], x["demosaic"]): x["psnr_db"] for x in acc["rows"]}
    mono = {i: psnr[("mono, rectangular", i, "fast")] for i in suite.INTERPOLATIONS}
    lin = by[("linear", "fast")]
    t_lin, min_lin = lin["timing"]["median_s"], lin["timing"]["min_s"]
    lines = [
        f"Decode: linear takes {t_lin:.2f} s per {dec['mpx']:.0f} Mpx capture (fastest run {min_lin:.2f} s; target "
        f"{suite.DECODE_TARGET_S:g} s: {'met' if lin['meets_target'] else 'missed'} by the median, "
        f"{'met' if min_lin <= suite.DECODE_TARGET_S else 'missed'} by the fastest run) and reaches {mono['linear']:.1f} dB. "
        "Against linear (ratios of the fastest runs, the least disturbed by other load): "
        + "; ".join(f"{i} {by[(i, 'fast')]['timing']['min_s'] / min_lin:.1f}× the time for "
                    f"{mono[i] - mono['linear']:+.1f} dB" for i in ("nearest", "cubic", "lanczos")) + "."]
    comp = dec["components"]
    parts = [f"`cv2.remap` {lin['remap_floor_s']:.2f} s", f"demosaicing {comp['demosaic_fast_s']:.2f} s"]
    if "hex_to_rect_s" in comp:
        parts.append(f"the hexagonal-to-rectangular pass (`hex_to_rect`, numpy) {comp['hex_to_rect_s']:.2f} s")
    lines.append(f"Of the linear decode's {t_lin:.2f} s: " + ", ".join(parts) + f"; copying the sensor takes "
                 f"{dec['copy_floor_s']:.3f} s, so memory traffic is not the limit.")
    exponent = r["decode_scaling"]["fit"]["exponent"]
    lines.append(f"Decode cost grows as size^{exponent:.2f}: {_growth(exponent)}.")
    bayer = {k[2]: v for k, v in psnr.items() if k[0] == "RGGB, rectangular" and k[1] == "linear"}
    if bayer:
        lines.append(f"Bayer captures decode to {bayer['fast']:.1f} dB (fast) / {bayer['careful']:.1f} dB (careful) "
                     f"against {mono['linear']:.1f} dB for the same optics in monochrome: demosaicing, not "
                     f"resampling, limits colour captures. Careful demosaicing takes {comp['demosaic_careful_s']:.2f} s "
                     f"against {comp['demosaic_fast_s']:.2f} s for fast on the big capture, for "
                     f"{bayer['careful'] - bayer['fast']:+.1f} dB on this scene.")
    rows = {(x["case"], x["interpolation"], x["upsample"]): x for x in rf["rows"]}
    gather = rows[("integer a", "(gather)", 1)]
    real = {i: rows[("real a", i, 1)] for i in suite.REFOCUS_INTERPOLATIONS}
    lines.append(
        f"Refocus: an integer slice costs {gather['ratio_to_floor']:.2f}× the memory floor "
        f"({gather['gb_per_s']:.1f} GB/s); a real slice {real['nearest']['ratio_to_floor']:.1f}× / "
        f"{real['linear']['ratio_to_floor']:.1f}× / {real['cubic']['ratio_to_floor']:.1f}× (nearest / linear / "
        f"cubic) with plane PSNR {real['nearest']['plane_psnr_db']:.1f} / {real['linear']['plane_psnr_db']:.1f} / "
        f"{real['cubic']['plane_psnr_db']:.1f} dB: cubic is the accurate choice for real a, linear blurs "
        f"(it averages neighbouring lenses). Every case matches the float64 reference to "
        f"{max(x['max_rel_error_vs_float64'] for x in rf['rows']):.1e} of the signal (float32 rounding).")
    sc = rf["scaling"]
    lines.append(f"Slices per call: {sc['slices'][-1]} integer slices cost "
                 f"{sc['integer_s'][-1] / sc['integer_s'][0]:.1f}× one slice (exponent "
                 f"{sc['integer_fit']['exponent']:.2f}), {sc['slices'][-1]} real ones "
                 f"{sc['real_linear_s'][-1] / sc['real_linear_s'][0]:.1f}× (exponent "
                 f"{sc['real_linear_fit']['exponent']:.2f}); separate calls would cost {sc['slices'][-1]}×: pass "
                 "all slices to one call.")
    ge = r["geometry"]
    thin = ge["thin_vs_thick"]
    lines.append(f"Geometry costs nothing ({ge['m_values_per_s']:.0f} M slices/s) and reproduces Table 2 to "
                 f"{bl.fmt(ge['table2_max_abs_err_mm_without_d0_minus'], 2)} mm (d₀₋: "
                 f"{bl.fmt(ge['table2_max_abs_err_mm'], 2)} mm). The thin-lens model (principal-plane gaps 0) moves "
                 f"every distance by {_span([x['diff_mm'] for x in thin], 'mm')} "
                 f"({_span([abs(x['diff_percent']) for x in thin], '%', 0)}; the principal planes only shift the path "
                 "from sensor to main lens), DOF unchanged — far beyond the paraxial model's own 0.5 % error near the camera: give the gaps.")
    cal = r["calibrate"]["rows"]
    big = [x for x in cal if not x.get("fine_white")][-1]
    lines.append(f"Calibration: centre RMS at most {max(x['centre_rms_px'] for x in cal):.4f} px; "
                 f"{big['timing']['median_s']:.0f} s for the {big['mpx']:.0f} Mpx white image, once per "
                 "camera setting (save GRID.json, then pass --calib).")
    return lines


def write_outputs(results: dict, out_dir: Path) -> None:
    from lfproc.atomic import write_json_atomic, write_text_atomic

    out_dir.mkdir(parents=True, exist_ok=True)
    sc, rf = results["decode_scaling"], results["refocus"]
    cal = [x for x in results["calibrate"]["rows"] if not x.get("fine_white")]
    bl.plot_scaling(str(out_dir / "benchmarks.png"), [p["mpx"] for p in sc["points"]],
                    [p["median_s"] for p in sc["points"]], sc["fit"], rf["scaling"]["slices"],
                    rf["scaling"]["integer_s"], rf["scaling"]["integer_fit"],
                    calibrate_sizes_mpx=[x["mpx"] for x in cal], calibrate_times_s=[x["timing"]["median_s"] for x in cal],
                    refocus_floor_s=rf["floor"]["median_s"], refocus_real_times_s=rf["scaling"]["real_linear_s"],
                    refocus_real_fit=rf["scaling"]["real_linear_fit"])
    write_json_atomic(out_dir / "benchmarks.json", results)
    write_text_atomic(out_dir / "benchmarks.md", render_markdown(results))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small captures, 1 repeat: a ~1 minute smoke run")
    parser.add_argument("--repeats", type=int, default=None, help="timed runs per case (default 3; quick: 1)")
    parser.add_argument("--out-dir", type=Path, default=None,
                        help="where benchmarks.{md,json,png} go (default docs/; quick: a temporary folder)")
    args = parser.parse_args(argv)
    if args.repeats is not None and args.repeats < 1:
        parser.error("--repeats must be >= 1")
    s = suite.settings_for(args.quick, args.repeats)
    out_dir = args.out_dir or (Path(tempfile.gettempdir()) / "lfproc-bench-quick" if s.quick else ROOT / "docs")
    results = run(s)
    write_outputs(results, out_dir)
    suite.log(f"done in {results['total_s']:.0f} s; wrote {out_dir / 'benchmarks.md'}, .json and .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
