"""Decoding benchmarks: the refocus bias, colour fidelity, and the time and peak memory of an Illum-sized decode.

    python scripts/bench_decode.py [--out docs] [--skip-illum]

1. **Refocus bias** (issue 13): the a at which a fine sweep of refocused slices is sharpest, against the
   true a of a rendered plane, for this decoder and for the previous one (every lit view delivered).
   The focus measure is the one of ``tests/test_decode_bias.py`` (spline shift-and-sum, unbiased).
2. **Colour fidelity** (issue 14): decoded views against the simulator's ideal views, per channel, on a
   grey card and on a textured plane (RGGB, 12 px lenses, m̂ = 11, rotated lattice), both demosaicing
   methods: the spread (1st–99th percentile) of each channel on the grey card and the RMS error relative
   to the channel's mean on the texture, over the views the decoder delivers and lenses off the border.
3. **Illum-sized decode** (issue 14): a 7728 × 5368 GRBG sensor under 14.29 px hexagonal lenses, m̂ = 15.
   Each measurement is a fresh process; peak memory is its maximum resident set size (``getrusage``).
   The floor holds what any decoder must: the two 16-bit sensor images and the output views. The
   straightforward implementation is the previous ``lfproc/decode.py`` (git commit 3cabae7): a full
   demosaiced float32 image, full float64 sample positions, full-size maps and temporaries. Whole
   Whole commands on the same sensor: ``scripts/bench_commands.py``.

Writes ``docs/benchmarks-decode.md`` and ``.json``.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import os
import platform
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402  (this folder)
import benchsim as suite  # noqa: E402
from lfproc.camera import MainLens

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
SENSOR = (5368, 7728)
OLD_COMMIT = "3cabae7"


# ----------------------------------------------------------------------------- 1. bias
def bias_rows() -> list[dict]:
    from test_decode_bias import render, sweep_peak

    from lfproc.decode import make_decoder

    rows = []
    for kind in ("rectangular", "hexagonal"):
        for cfa in ("RGGB", "none"):
            cam, a_true, raw, white, grid = render(kind, cfa)
            new = make_decoder(white, grid, cam.m_hat, cfa)
            old = make_decoder(white, grid, cam.m_hat, cfa, centroid_tolerance=None)
            rows.append({"grid": kind, "cfa": cfa, "a_true": a_true, "m_hat": cam.m_hat,
                         "peak_new": sweep_peak(new(raw), a_true, new.views_delivered),
                         "views_new": int(new.views_delivered.sum()),
                         "peak_old": sweep_peak(old(raw), a_true - 0.15, half_width=0.2),
                         "views_old": int(old.views_delivered.sum())})
            print("bias", rows[-1], flush=True)
    return rows


# ----------------------------------------------------------------------------- 2. colour
def colour_scene(kind: str):
    from lfproc import Camera, geometry, simulate
    from lfproc.simulate import Noise, Plane, Scene, Uniform

    cam = Camera(0.005, 0.06, 0.24, MainLens(50.0, 50.0, f_number=4.0), grid="rectangular", cfa="RGGB", black_level=0, white_level=65535)
    distance = geometry.slice_distance_mm(cam, 1.0)
    feature = 4 * cam.mla_pitch_mm * (distance - cam.main_optics.sensor_path_mm(cam.mla_path_mm)) / cam.main_optics.focal_length_mm
    texture = Uniform(0.5) if kind == "grey card" else Noise(feature_mm=feature, seed=3)
    scene = Scene((Plane(distance, texture, tint=(1.0, 1.0, 1.0) if kind == "grey card" else (0.9, 0.7, 0.5)),),
                  background=0.1)
    noise = dict(shot_noise_photons=4000, read_noise_dn=20) if kind == "grey card" else {}
    sim = simulate.render(cam, scene, (360, 480), rotation_deg=-0.4, rim_radius_mm=None, pixel_samples=3,
                          aperture_samples=3, seed=2, **noise)
    scale = np.float32(1.0 / (65535 * 0.8))   # radiance 1 reaches 80 % of the range (exposure 0.8)
    return cam, sim, sim.raw.astype(np.float32) * scale, sim.white.astype(np.float32) * scale


def colour_stats(views, ideal, weight, delivered) -> dict:
    if weight is not None:
        mask = (weight > 0.999) & delivered[:, :, None, None]
    else:   # every sample the decoder outputs as signal (not 0)
        mask = delivered[:, :, None, None] & (views.max(axis=-1) != 0)
    mask[:, :, [0, -1], :] = False
    mask[:, :, :, [0, -1]] = False
    out = {}
    for ch, name in enumerate("RGB"):
        got = views[..., ch][mask]
        want = ideal[..., ch][mask] if ideal is not None else np.full_like(got, 0.5)
        out[name] = {"p1": float(np.percentile(got, 1)), "p99": float(np.percentile(got, 99)),
                     "min": float(got.min()), "max": float(got.max()),
                     "rel_rms": float(np.sqrt(np.mean((got - want) ** 2)) / np.mean(want)),
                     "mean_ratio": float(np.mean(got) / np.mean(want))}
    return out


def colour_rows() -> list[dict]:
    from lfproc.decode import make_decoder

    rows = []
    for scene in ("grey card", "texture"):
        cam, sim, raw, white = colour_scene(scene)
        for method in ("fast", "careful"):
            for label, tol in (("new", 0.1), ("old", None)):
                dec = make_decoder(white, sim.grid, cam.m_hat, "RGGB", demosaic_method=method,
                                   centroid_tolerance=tol)
                delivered = dec.views_delivered if tol else np.ones_like(dec.views_delivered)
                if scene == "grey card":
                    stats = colour_stats(dec(raw), None, None, delivered)
                else:
                    stats = colour_stats(dec(raw), sim.ideal_views, sim.ideal_weight, delivered)
                rows.append({"scene": scene, "demosaic": method, "decoder": label, "channels": stats})
                print("colour", rows[-1], flush=True)
    return rows


# ----------------------------------------------------------------------------- 3. Illum-sized decode
def make_illum(folder: Path) -> dict:
    """White image and capture (10-bit in uint16, black 0) of anti-aliased disks on the exact lattice, as .npy
    (the generator of scripts/bench_commands.py)."""
    import dataclasses

    sys.path.insert(0, str(ROOT / "scripts"))
    from bench_commands import illum_camera, illum_frames, illum_grid

    camera = dataclasses.replace(illum_camera(), black_level=0.0, name="")
    grid = illum_grid(camera)
    white, capture = illum_frames(grid, black=0.0)
    np.save(folder / "white.npy", white)
    np.save(folder / "capture.npy", capture)
    (folder / "grid.json").write_text(json.dumps(grid.to_json_dict() | {"centers_xy_px": []}))
    return {"grid": [grid.kind, grid.rows, grid.cols, grid.pitch_px], "m_hat": camera.m_hat, "cfa": camera.cfa}


CHILD = textwrap.dedent("""
    import json, resource, sys, time
    import numpy as np
    folder, mode = sys.argv[1], sys.argv[2]
    from lfproc import LensGrid
    grid = LensGrid.from_json_dict(json.load(open(folder + "/grid.json")))
    white = np.load(folder + "/white.npy")
    capture = np.load(folder + "/capture.npy")
    t0 = time.perf_counter()
    if mode == "floor":
        from lfproc.decode import rect_row_count
        views = np.empty((15, 15, rect_row_count(grid.rows), grid.cols - 1, 3), np.float32)
        views.fill(1.0)
        t1 = t0
    else:
        if mode == "old":
            sys.path.insert(0, folder)
            from old_decode import make_decoder
        else:
            from lfproc.decode import make_decoder
        dec = make_decoder(white, grid, 15, "GRBG")
        t1 = time.perf_counter()
        views = dec(capture, "GRBG")
    t2 = time.perf_counter()
    print(json.dumps({"mode": mode, "prepare_s": t1 - t0, "decode_s": t2 - t1, "shape": list(views.shape),
                      "views_gb": views.nbytes / 1e9,
                      "peak_gb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9}))
""")


def illum_rows(folder: Path) -> list[dict]:
    old = subprocess.run(["git", "show", f"{OLD_COMMIT}:lfproc/decode.py"], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout
    old = old.replace("from .errors import", "from lfproc.errors import").replace("from .grid import",
                                                                                   "from lfproc.grid import")
    (folder / "old_decode.py").write_text(old)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    rows = []
    for mode in ("floor", "new", "old"):
        proc = subprocess.run([sys.executable, "-c", CHILD, str(folder), mode], capture_output=True, text=True,
                              env=env)
        if proc.returncode:
            raise SystemExit(f"{mode}: {proc.stderr[-800:]}")
        rows.append(json.loads(proc.stdout.strip().splitlines()[-1]))
        print("illum", rows[-1], flush=True)
    return rows


# ----------------------------------------------------------------------------- report
def markdown(result: dict) -> str:
    lines = ["# Decoding benchmarks", "",
             f"Machine: {result['machine']}. Date: {result['date']}. Written by `scripts/bench_decode.py`.", ""]
    if result.get("bias"):
        lines += ["## Refocus bias (issue 13)", "",
                  "Sharpest slice of a fine sweep (spline shift-and-sum, see `tests/test_decode_bias.py`) "
                  "against the plane's true a. *Old*: every lit view delivered (the previous decoder).", "",
                  "| grid | CFA | m̂ | true a | peak (this decoder) | views | peak (old) | views (old) |",
                  "| --- | --- | --- | --- | --- | --- | --- | --- |"]
        for r in result["bias"]:
            lines.append(f"| {r['grid']} | {r['cfa']} | {r['m_hat']} | {r['a_true']:.3f} | {r['peak_new']:.4f} | "
                         f"{r['views_new']} | {r['peak_old']:.4f} | {r['views_old']} |")
        lines.append("")
    if result.get("colour"):
        lines += ["## Colour fidelity against the simulator's ideal views (issue 14)", "",
                  "RGGB render, 12 px lenses, m̂ = 11, lattice rotated −0.4°. Grey card (0.5, shot noise of 4000 "
                  "photons at full scale, 20 DN read noise; one raw pixel ratio has σ = 0.016): 1st–99th "
                  "percentile of each channel, (min–max). Texture: RMS error relative to the channel mean, "
                  "and the mean's ratio to the ideal. Over delivered views (old: all views) at full "
                  "ideal weight, lenses off the border.", "",
                  "| scene | demosaic | decoder | R | G | B |", "| --- | --- | --- | --- | --- | --- |"]
        for r in result["colour"]:
            cells = []
            for name in "RGB":
                c = r["channels"][name]
                cells.append(f"{c['p1']:.3f}–{c['p99']:.3f} ({c['min']:.2f}–{c['max']:.2f})"
                             if r["scene"] == "grey card"
                             else f"{100 * c['rel_rms']:.2f} % (×{c['mean_ratio']:.3f})")
            lines.append(f"| {r['scene']} | {r['demosaic']} | {r['decoder']} | " + " | ".join(cells) + " |")
        lines.append("")
    if result.get("illum"):
        info = result["illum_setup"]
        lines += ["## Illum-sized decode: time and peak memory (issue 14)", "",
                  f"7728 × 5368 GRBG sensor, {info['grid'][0]} lenses of {info['grid'][3]:.2f} px "
                  f"({info['grid'][1]} × {info['grid'][2]}), m̂ = {info['m_hat']}; decoder built from the white "
                  "image, then one capture decoded; fresh process each, peak = max RSS (interpreter and "
                  "libraries included). Floor: the two sensor images plus the output views, nothing else.", "",
                  "| run | views | prepare (s) | decode (s) | peak RSS (GB) | ratio to floor |",
                  "| --- | --- | --- | --- | --- | --- |"]
        floor = next(r for r in result["illum"] if r["mode"] == "floor")["peak_gb"]
        names = {"floor": "floor", "new": "this decoder", "old": "previous decoder (straightforward)"}
        for r in result["illum"]:
            lines.append(f"| {names[r['mode']]} | {' × '.join(map(str, r['shape']))} | {r['prepare_s']:.2f} | "
                         f"{r['decode_s']:.2f} | {r['peak_gb']:.2f} | {r['peak_gb'] / floor:.2f} |")
        lines.append("")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs"))
    parser.add_argument("--skip-illum", action="store_true")
    parser.add_argument("--only", choices=["bias", "colour", "illum"])
    args = parser.parse_args(argv)
    result = {"machine": f"{platform.machine()}, {os.cpu_count()} CPUs, {platform.python_version()}",
              "date": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    if args.only in (None, "bias"):
        result["bias"] = bias_rows()
    if args.only in (None, "colour"):
        result["colour"] = colour_rows()
    if args.only in (None, "illum") and not args.skip_illum:
        with tempfile.TemporaryDirectory(prefix="lfproc-bench-decode-") as tmp:
            result["illum_setup"] = make_illum(Path(tmp))
            result["illum"] = illum_rows(Path(tmp))
    out = Path(args.out)
    json_path = out / "benchmarks-decode.json"
    if json_path.exists() and args.only:      # keep the other sections of an earlier full run
        result = json.loads(json_path.read_text()) | result
    json_path.write_text(json.dumps(result, indent=1))
    (out / "benchmarks-decode.md").write_text(markdown(result))
    print(f"wrote {out / 'benchmarks-decode.md'}")
    return 0


# ----------------------------------------------------------------------------- the stage of scripts/bench.py
def remap_floor(image: np.ndarray, grid, m_hat: int, interpolation: str, repeats: int) -> float:
    """Median time of cv2.remap alone: the decoder's sample maps (float32, precomputed) into one output."""
    import cv2

    from lfproc.decode import sample_positions

    flag = {"nearest": cv2.INTER_NEAREST, "linear": cv2.INTER_LINEAR, "cubic": cv2.INTER_CUBIC,
            "lanczos": cv2.INTER_LANCZOS4}[interpolation]
    x, y = sample_positions(grid, m_hat)
    maps = [(np.ascontiguousarray(x[k].reshape(-1, grid.cols), dtype=np.float32),
             np.ascontiguousarray(y[k].reshape(-1, grid.cols), dtype=np.float32)) for k in range(m_hat)]
    del x, y
    out = np.empty((m_hat, m_hat * grid.rows, grid.cols, image.shape[2]), dtype=np.float32)

    def run():
        for k, (mx, my) in enumerate(maps):
            cv2.remap(image, mx, my, flag, dst=out[k], borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    return bl.measure(run, repeats, memory=False).median_s


def stage_decode_speed(raw: np.ndarray, white: np.ndarray, grid, camera, s: suite.Settings) -> tuple[dict, np.ndarray]:
    """Decode the big capture with every interpolation and demosaic; floors; the component costs."""
    from lfproc.decode import hex_to_rect, make_decoder, to_channels

    mpx = raw.size / 1e6
    small = (min(raw.shape[0], 400), min(raw.shape[1], 560))
    where, small_grid = suite.centre_crop(camera, raw.shape, small)
    small_raw, small_white = raw[where], white[where]
    make_decoder(small_white, small_grid, camera.m_hat, camera.cfa)(small_raw)   # imports, OpenCV start-up
    decoder, prepare_s = bl.time_once(lambda: make_decoder(white, grid, camera.m_hat, camera.cfa,
                                                           interpolation="linear", demosaic_method="fast"))
    copy_floor = bl.measure(lambda: raw.copy(), s.cheap_repeats, memory=False).median_s
    rows, views = [], None
    cases = [(interp, "fast") for interp in suite.INTERPOLATIONS] + [("linear", "careful")]
    for interp, method in cases:
        # the same decoder with another interpolation/demosaic for the capture: the per-capture call is
        # what is timed; make_decoder (the white image's share) is timed once, for linear/fast
        dec = dataclasses.replace(decoder, interpolation=interp, demosaic_method=method)
        timing, result = bl.measure_keeping(lambda: dec(raw), s.repeats)
        rows.append({"interpolation": interp, "demosaic": method, "timing": timing.as_dict(),
                     "mpx_per_s": mpx / timing.median_s, "ratio_to_copy": timing.median_s / copy_floor,
                     "meets_target": timing.median_s <= suite.DECODE_TARGET_S})
        suite.log(f"  decode {interp}/{method}: {timing.median_s:.2f} s (peak {timing.peak_mb:.0f} MB)")
        if interp == "linear" and method == "fast":
            views = result
        del result
    image = to_channels(raw, camera.cfa, "fast")
    for row in rows:
        if row["demosaic"] == "fast":
            row["remap_floor_s"] = remap_floor(image, grid, camera.m_hat, row["interpolation"], s.repeats)
            row["ratio_to_remap"] = row["timing"]["median_s"] / row["remap_floor_s"]
    components = {
        "demosaic_fast_s": bl.measure(lambda: to_channels(raw, camera.cfa, "fast"), s.cheap_repeats, memory=False).median_s,
        "demosaic_careful_s": bl.measure(lambda: to_channels(raw, camera.cfa, "careful"), s.cheap_repeats,
                                         memory=False).median_s,
    }
    if grid.kind == "hexagonal":
        raw_views = decoder.inverse_white   # hexagonal-lattice views, the shape hex_to_rect receives
        components["hex_to_rect_s"] = bl.measure(lambda: hex_to_rect(raw_views, grid), s.cheap_repeats,
                                                 memory=False).median_s
    result = {"sensor_shape": list(raw.shape), "mpx": mpx, "lens_grid": [grid.rows, grid.cols, grid.kind],
              "views_shape": list(views.shape), "views_gb": views.nbytes / 1e9, "prepare_s": prepare_s,
              "copy_floor_s": copy_floor, "rows": rows, "components": components}
    return result, views


def stage_decode_scaling(raw, white, camera, s: suite.Settings, full_row: dict) -> dict:
    """Decode (linear, fast) time against sensor size: central crops of the big capture, exact crop grids."""
    from lfproc.decode import make_decoder

    points = []
    for shape in suite.crop_shapes(raw.shape):
        if tuple(shape) == tuple(raw.shape):
            median = full_row["timing"]["median_s"]
        else:
            where, grid = suite.centre_crop(camera, raw.shape, shape)
            crop_raw, crop_white = np.ascontiguousarray(raw[where]), np.ascontiguousarray(white[where])
            dec = make_decoder(crop_white, grid, camera.m_hat, camera.cfa)
            median = bl.measure(lambda: dec(crop_raw), s.cheap_repeats, memory=False).median_s
        points.append({"sensor_shape": list(shape), "mpx": shape[0] * shape[1] / 1e6, "median_s": median})
        suite.log(f"  decode scaling {shape}: {median:.3f} s")
    fit = bl.power_law_fit([p["mpx"] for p in points], [p["median_s"] for p in points])
    return {"points": points, "fit": fit}


def render_psnr_capture(camera, s: suite.Settings):
    from lfproc import simulate

    tint = (1.0, 0.7, 0.4) if camera.cfa != "none" else (1.0, 1.0, 1.0)
    return simulate.render(camera, suite.noise_scene(camera, 1.0, tint), s.psnr_shape, rotation_deg=0.4,
                           offset_px=(0.3, -0.2), rim_radius_mm=None, pixel_samples=s.psnr_pixel_samples,
                           aperture_samples=s.psnr_aperture_samples, seed=1)


def psnr_row(label: str, sim, interp: str, method: str, rings: int = 1) -> dict:
    """PSNR of one capture decoded with ``interp``/``method`` against the simulator's ideal views (see
    :func:`stage_decode_accuracy`), and of the outer views it leaves out."""
    from lfproc.decode import decode, hex_to_rect

    cam = sim.camera
    views = decode(suite.normalised(sim.raw, cam), suite.normalised(sim.white, cam), sim.grid, cam.m_hat, cam.cfa,
                   interpolation=interp, demosaic_method=method)
    ideal, weight = sim.ideal_views, sim.ideal_weight
    if sim.grid.kind == "hexagonal":
        ideal, _ = hex_to_rect(ideal, sim.grid)
        weight = hex_to_rect(weight[..., None], sim.grid)[0][..., 0]
    kind = sim.grid.kind
    mask = bl.decode_psnr_mask(weight, kind, rings_excluded=rings)
    value = bl.psnr_db(views[mask], ideal[mask])
    outer = bl.decode_psnr_mask(weight, kind, rings_excluded=-1) & ~mask
    outer_db = bl.psnr_db(views[outer], ideal[outer]) if outer.any() else None
    suite.log(f"  PSNR {label} {interp}/{method}: {value:.1f} dB")
    return {"capture": label, "interpolation": interp, "demosaic": method, "psnr_db": value,
            "outer_ring_psnr_db": outer_db, "rings_excluded": rings,
            "meets_target": value >= suite.PSNR_TARGET_DB if interp != "nearest" else None}


def stage_decode_accuracy(s: suite.Settings) -> dict:
    """PSNR of decoded views against the simulator's ideal views (9 µm pixels, 250 µm lenses, m̂ = 25)."""
    start = time.perf_counter()
    mono = render_psnr_capture(suite.paper_9um_camera(), s)
    rows = [psnr_row("mono, rectangular", mono, interp, "fast") for interp in suite.INTERPOLATIONS]
    bayer = render_psnr_capture(suite.paper_9um_camera("RGGB"), s)
    rows += [psnr_row("RGGB, rectangular", bayer, "linear", method) for method in ("fast", "careful")]
    rows.append(psnr_row("RGGB, rectangular", bayer, "cubic", "careful"))
    hexa = render_psnr_capture(suite.paper_9um_camera(grid="hexagonal"), s)
    rows.append(psnr_row("mono, hexagonal", hexa, "linear", "fast"))
    # convergence: one more sample per axis must not change the PSNR (the reference is not the limit)
    finer = dataclasses.replace(s, psnr_pixel_samples=s.psnr_pixel_samples + 1,
                                psnr_aperture_samples=s.psnr_aperture_samples + 1)
    rows.append(psnr_row(f"mono, rectangular, {finer.psnr_pixel_samples}²×{finer.psnr_aperture_samples}² samples",
                         render_psnr_capture(suite.paper_9um_camera(), finer), "linear", "fast"))
    return {"sensor_shape": list(s.psnr_shape), "pixel_samples": s.psnr_pixel_samples,
            "aperture_samples": s.psnr_aperture_samples, "rows": rows,
            "seconds_incl_render": time.perf_counter() - start}


def suite_section(r: dict) -> list[str]:
    """The decode section of docs/benchmarks.md (``scripts/bench.py``)."""
    out = []
    dec, acc, sc = r["decode"], r["decode_accuracy"], r["decode_scaling"]
    comp = dec["components"]
    out += ["## Decode (`lfproc.decode.make_decoder` + call)", "",
            f"Speed on the {dec['sensor_shape'][1]} × {dec['sensor_shape'][0]} px capture ({dec['mpx']:.1f} Mpx, "
            f"{dec['lens_grid'][0]} × {dec['lens_grid'][1]} hexagonal lenses → views "
            f"{' × '.join(str(v) for v in dec['views_shape'])} float32 = {dec['views_gb']:.2f} GB). Target ≤ "
            f"{suite.DECODE_TARGET_S:g} s. `make_decoder` (demosaic and resample the white image, once per white "
            f"image) took {dec['prepare_s']:.2f} s for linear/fast; the table times the per-capture call. "
            f"Floors: a numpy copy of the sensor ({bl.fmt(dec['copy_floor_s'])} s) and `cv2.remap` alone with the "
            f"decoder's float32 maps on the demosaiced image, same interpolation.", "",
            bl.markdown_table(["interpolation", "demosaic", "time s (min)", "Mpx/s", "× remap floor", "× copy",
                               "peak MB", f"≤ {suite.DECODE_TARGET_S:g} s (median / fastest)"],
                              [[x["interpolation"], x["demosaic"], bl.fmt_timing(x["timing"]), x["mpx_per_s"],
                                x.get("ratio_to_remap"), x["ratio_to_copy"], bl.fmt_peak(x["timing"]),
                                ("yes" if x["meets_target"] else "no") + " / "
                                + ("yes" if x["timing"]["min_s"] <= suite.DECODE_TARGET_S else "no")]
                               for x in dec["rows"]]), "",
            "Where the time goes (medians, same capture): demosaic fast "
            f"{bl.fmt(comp['demosaic_fast_s'])} s, careful {bl.fmt(comp['demosaic_careful_s'])} s"
            + (f"; hexagonal → rectangular resampling (`hex_to_rect`) {bl.fmt(comp['hex_to_rect_s'])} s"
               if "hex_to_rect_s" in comp else "")
            + "; `cv2.remap` as in the floor column; the rest is the white-image multiply.", "",
            f"Accuracy: PSNR of the decoded views against the simulator's ideal views, {acc['sensor_shape'][1]} × "
            f"{acc['sensor_shape'][0]} px captures of the paper's f100 camera with 9 µm pixels under 250 µm lenses "
            f"(27.8 px → m̂ = 25), a noise texture on the plane of slice a = 1, rendered with "
            f"{acc['pixel_samples']}² pixel × {acc['aperture_samples']}² aperture samples. Compared: samples all of "
            f"whose rays pass, lenses off the border, views whose sample lies at least 1.5 effective pixels inside "
            f"the lens's cell: all but the outer ring on a rectangular lattice; the outer views read the neighbouring "
            f"micro image (crosstalk) and are listed separately. The last row repeats the first linear row with one "
            f"more sample per axis: the reference has converged when it barely moves. Target ≥ {suite.PSNR_TARGET_DB:g} dB (linear).", "",
            bl.markdown_table(["capture", "interpolation", "demosaic", "PSNR dB", "outer views PSNR dB"],
                              [[x["capture"], x["interpolation"], x["demosaic"], x["psnr_db"],
                                x["outer_ring_psnr_db"]] for x in acc["rows"]]), "",
            "Hexagonal: the decoded views are compared with the ideal views passed through the same "
            "`hex_to_rect`, so the row measures the decoding, not the hexagonal-to-rectangular interpolation.", "",
            "### Decode time against sensor size (linear, fast demosaic)", "",
            bl.markdown_table(["sensor px", "Mpx", "time s", "Mpx/s"],
                              [[f"{p['sensor_shape'][1]} × {p['sensor_shape'][0]}", p["mpx"], p["median_s"],
                                p["mpx"] / p["median_s"]] for p in sc["points"]]), "",
            f"Fit: time ∝ size^{sc['fit']['exponent']:.2f} (R² = {sc['fit']['r2']:.3f}).", ""]
    return out


if __name__ == "__main__":
    sys.exit(main())
