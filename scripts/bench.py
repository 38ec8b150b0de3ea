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

Usage: ``python scripts/bench.py [--quick] [--repeats N] [--out-dir DIR]``. The full run takes about
8 minutes on 2 cores and writes to ``docs/``; ``--quick`` is a ~1 minute smoke run on smaller captures
that writes to a temporary folder unless ``--out-dir`` is given.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import benchlib as bl  # noqa: E402  (the script's own folder)

ROOT = Path(__file__).resolve().parent.parent
CAMERAS = ROOT / "samples" / "cameras"

LYTRO_SHAPE = (5368, 7728)           # Lytro Illum sensor, rows × columns
LYTRO_ROTATION_DEG = 0.17            # a realistic small lattice rotation
LYTRO_OFFSET_PX = (0.31, -0.27)
INTERPOLATIONS = ("nearest", "linear", "cubic", "lanczos")
REFOCUS_INTERPOLATIONS = ("nearest", "linear", "cubic")
INTEGER_A = 2.0
REAL_A = 1.37                        # generic fractional sample positions
SLICE_COUNTS = (1, 2, 5, 10, 20)
AREA_FRACTIONS = (1 / 16, 1 / 8, 1 / 4, 1 / 2, 1.0)   # decode scaling sizes, as fractions of the big sensor
DECODE_TARGET_S = 3.0
PSNR_TARGET_DB = 35.0
GEOMETRY_SAMPLES = 1_000_000

# the paper's Table 2 (f100, b_U = f_U): a -> (d_a-, d_a, d_a+), prediction and Zemax simulation
TABLE2_PREDICTED = {0: (3483.174, math.inf, math.inf), 1: (301.538, 313.066, 325.596),
                    2: (236.606, 241.017, 245.616), 3: (214.369, 217.001, 219.707),
                    4: (203.136, 204.993, 206.889), 5: (196.359, 197.788, 199.241)}
TABLE2_ZEMAX = {0: (3863.248, math.inf, math.inf), 1: (301.518, 312.889, 324.189),
                2: (236.565, 240.914, 245.01), 3: (214.289, 216.809, 219.37),
                4: (202.917, 204.764, 206.647), 5: (195.99, 197.442, 198.905)}
# Table 4: (i, gap) -> (baseline mm, |tilt| b_U1, |tilt| b_U2 in degrees)
TABLE4 = {(-1, 1): (0.362, 0.000, 0.042), (-12, 12): (4.344, 0.000, 0.504), (-12, 24): (8.688, 0.000, 0.504)}


@dataclasses.dataclass(frozen=True)
class Settings:
    """Sizes and repeats of one run (full or quick)."""

    quick: bool
    repeats: int              # the slow cases: decoding the big capture, calibration
    cheap_repeats: int        # cases under about a second: more runs, steadier medians
    big_shape: tuple          # the "Lytro-sized" sensor of this run
    psnr_shape: tuple         # captures rendered with ideal views
    psnr_pixel_samples: int
    psnr_aperture_samples: int
    refocus_accuracy_lenses: tuple
    calibrate_single_big: bool   # also calibrate the big white once (not repeated: slow)
    fresh_compile: bool          # time numba compilation in a subprocess with an empty cache


def settings_for(quick: bool, repeats: int | None) -> Settings:
    if quick:
        return Settings(True, repeats or 1, repeats or 1, (1342, 1932), (168, 224), 2, 3, (32, 40), False, True)
    return Settings(False, repeats or 3, max(5, repeats or 3), LYTRO_SHAPE, (336, 448), 4, 5, (64, 80), True, True)


def log(message: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {message}", flush=True)


# ============================================================================ cameras and captures
def lytro_camera():
    """A Lytro-Illum-like camera: 1.4 µm pixels, 20 µm hexagonal lenses (14.3 px), GRBG, f/2, m̂ = 15."""
    from lfproc import Camera

    return Camera(pixel_pitch_mm=0.0014, mla_pitch_mm=0.02, mla_focal_length_mm=0.04, main_focal_length_mm=50.0,
                  image_distance_mm=50.0, f_number=2.0, grid="hexagonal", cfa="GRBG", black_level=64.0,
                  white_level=1023.0, micro_image_px=15, name="lytro-illum-like")


def paper_9um_camera(cfa: str = "none", grid: str = "rectangular"):
    """The paper's f100 camera with 9 µm pixels: 27.8 px per lens, resampled to m̂ = 25 (Section 5.1)."""
    from lfproc import Camera

    cam = Camera.from_toml(CAMERAS / "paper-f100.toml")
    return dataclasses.replace(cam, pixel_pitch_mm=0.009, cfa=cfa, grid=grid)


def noise_scene(camera, a: float, tint=(1.0, 1.0, 1.0)):
    """One plane with band-limited noise at the distance that slice ``a`` focuses on."""
    from lfproc import geometry
    from lfproc.simulate import Noise, Plane, Scene

    d = geometry.slice_distance_mm(camera, a)
    feature = 4 * camera.mla_pitch_mm * (d - camera.sensor_to_main_lens_mm) / camera.main_focal_length_mm
    return Scene((Plane(d, Noise(feature_mm=feature, seed=1), tint=tint),), background=0.1)


def normalised(dn: np.ndarray, camera) -> np.ndarray:
    """16-bit DN to the linear float32 that ``read_capture`` returns."""
    return (dn.astype(np.float32) - np.float32(camera.black_level)) / np.float32(camera.white_level - camera.black_level)


def centre_crop(camera, full_shape, crop_shape) -> tuple[tuple[slice, slice], object]:
    """The central ``crop_shape`` of a capture rendered at ``full_shape``: its slices and its exact lens grid.

    The crop starts at even pixel indices (the Bayer phase is kept). The renderer anchors the lattice at
    the sensor centre plus the offset; in crop coordinates that point moves by the crop's origin, so the
    crop's grid is the simulator's default grid of the crop with the offset moved accordingly.
    """
    from lfproc import simulate

    y0 = 2 * ((full_shape[0] - crop_shape[0]) // 4)
    x0 = 2 * ((full_shape[1] - crop_shape[1]) // 4)
    dx = (full_shape[1] - crop_shape[1]) / 2.0 - x0 + LYTRO_OFFSET_PX[0]
    dy = (full_shape[0] - crop_shape[0]) / 2.0 - y0 + LYTRO_OFFSET_PX[1]
    grid = simulate.default_grid(camera, crop_shape, LYTRO_ROTATION_DEG, (dx, dy))
    return (slice(y0, y0 + crop_shape[0]), slice(x0, x0 + crop_shape[1])), grid


def crop_shapes(big_shape) -> list[tuple[int, int]]:
    """Sensor sizes of the decode scaling: area fractions of the big sensor, even sides (Bayer phase)."""
    shapes = []
    for fraction in AREA_FRACTIONS:
        scale = math.sqrt(fraction)
        shapes.append((2 * int(round(big_shape[0] * scale / 2)), 2 * int(round(big_shape[1] * scale / 2))))
    return shapes


# ============================================================================ stages
def stage_read(raw_dn: np.ndarray, camera, s: Settings, tmp: str) -> dict:
    """read_capture of a 16-bit PNG and TIFF against OpenImageIO's own read and numpy.fromfile."""
    import cv2
    import OpenImageIO as oiio
    import tifffile

    from lfproc.io import read_capture

    paths = {"PNG": os.path.join(tmp, "raw.png"), "TIFF": os.path.join(tmp, "raw.tif")}
    if not cv2.imwrite(paths["PNG"], raw_dn):
        raise RuntimeError("cv2 could not write the PNG")
    tifffile.imwrite(paths["TIFF"], raw_dn)
    truth = (raw_dn.astype(np.float64) - camera.black_level) / (camera.white_level - camera.black_level)
    mpx = raw_dn.size / 1e6

    def oiio_native(path):
        inp = oiio.ImageInput.open(path)
        try:
            return inp.read_image(0, 0, 0, 1, "uint16")
        finally:
            inp.close()

    rows = []
    for fmt, path in paths.items():
        size_mb = os.path.getsize(path) / 1e6
        timing = bl.measure(lambda: read_capture(path, camera), s.cheap_repeats)
        floor = bl.measure(lambda: oiio_native(path), s.cheap_repeats, memory=False)
        data = read_capture(path, camera).data
        err = float(np.max(np.abs(data.astype(np.float64) - truth)))
        rows.append({"case": f"read_capture, 16-bit {fmt}", "file_mb": size_mb, "timing": timing.as_dict(),
                     "mpx_per_s": mpx / timing.median_s, "file_mb_per_s": size_mb / timing.median_s,
                     "floor": "OpenImageIO native uint16 read", "floor_s": floor.median_s,
                     "ratio_to_floor": timing.median_s / floor.median_s, "max_abs_error": err})
    fromfile = bl.measure(lambda: np.fromfile(paths["TIFF"], dtype=np.uint8), s.cheap_repeats, memory=False)
    return {"sensor_shape": list(raw_dn.shape), "rows": rows,
            "fromfile_tiff_s": fromfile.median_s,
            "fromfile_tiff_mb_per_s": os.path.getsize(paths["TIFF"]) / 1e6 / fromfile.median_s}


def lattice_errors(fitted, true) -> dict:
    """Centre RMS of the true lenses against the fitted lattice (extended by 10 lenses), pitch and rotation errors."""
    from lfproc.grid import LensGrid

    extended = LensGrid(fitted.kind, fitted.pitch_px, fitted.rotation_deg, tuple(fitted.lens_xy(-10, -10)),
                        fitted.rows + 20, fitted.cols + 20)
    rms = bl.nearest_distance_rms(true.centers_xy_px().reshape(-1, 2), extended.centers_xy_px().reshape(-1, 2))
    return {"centre_rms_px": rms, "pitch_error_px": fitted.pitch_px - true.pitch_px,
            "rotation_error_deg": fitted.rotation_deg - true.rotation_deg,
            "residual_rms_px": fitted.residual_rms_px, "kind_ok": fitted.kind == true.kind}


def stage_calibrate(white: np.ndarray, camera, s: Settings) -> dict:
    """estimate_grid on crops of the white image (repeated) and on the whole sensor (once, full run)."""
    from lfproc.calibrate import estimate_grid

    def calibrate(image):
        return estimate_grid(image, camera.grid, camera.pitch_px, cfa=camera.cfa)

    shapes = crop_shapes(white.shape)
    rows = []
    plan = [(shapes[0], s.repeats), (shapes[2], s.repeats)]
    if s.calibrate_single_big:
        plan.append((white.shape, 0))
    for shape, repeats in plan:
        where, truth = centre_crop(camera, white.shape, shape)
        crop = np.ascontiguousarray(white[where])
        if repeats:
            timing, fitted = bl.measure_keeping(lambda: calibrate(crop), repeats)
            runs = f"median of {repeats}"
        else:
            (fitted, seconds) = bl.time_once(lambda: calibrate(crop))
            timing = bl.Timing(seconds, seconds, [seconds], None)
            runs = "1 run"
        row = {"sensor_shape": list(shape), "mpx": crop.size / 1e6, "runs": runs, "timing": timing.as_dict(),
               "mpx_per_s": crop.size / 1e6 / timing.median_s, "lenses": truth.rows * truth.cols}
        row.update(lattice_errors(fitted, truth))
        rows.append(row)
        log(f"  calibrate {shape}: {timing.median_s:.2f} s, centre RMS {row['centre_rms_px']:.4f} px")
    rows.append(calibrate_fine_white(camera, shapes[0], calibrate))
    return {"rows": rows}


def calibrate_fine_white(camera, shape, calibrate) -> dict:
    """Calibration accuracy on a white image rendered with the simulator's default 2²×3² samples.

    The speed capture's white has one sample per pixel (aliased micro-image edges), which scatters the
    individual centres (the fit residual) though the fitted lattice stays accurate.
    """
    from lfproc import simulate

    dn, truth = simulate.render_white(camera, shape, rotation_deg=LYTRO_ROTATION_DEG, offset_px=LYTRO_OFFSET_PX,
                                      rim_radius_mm=None, pixel_samples=2, aperture_samples=3)
    fitted, seconds = bl.time_once(lambda: calibrate(normalised(dn, camera)))
    row = {"sensor_shape": list(shape), "mpx": dn.size / 1e6, "runs": "1 run, 2²×3²-sample white",
           "timing": bl.Timing(seconds, seconds, [seconds], None).as_dict(), "mpx_per_s": dn.size / 1e6 / seconds,
           "lenses": truth.rows * truth.cols, "fine_white": True}
    row.update(lattice_errors(fitted, truth))
    log(f"  calibrate {shape} (2x3-sample white): centre RMS {row['centre_rms_px']:.4f} px, "
        f"residual {row['residual_rms_px']:.4f} px")
    return row


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


def stage_decode_speed(raw: np.ndarray, white: np.ndarray, grid, camera, s: Settings) -> tuple[dict, np.ndarray]:
    """Decode the big capture with every interpolation and demosaic; floors; the component costs."""
    from lfproc.decode import hex_to_rect, make_decoder, to_channels

    mpx = raw.size / 1e6
    small = (min(raw.shape[0], 400), min(raw.shape[1], 560))
    where, small_grid = centre_crop(camera, raw.shape, small)
    small_raw, small_white = raw[where], white[where]
    make_decoder(small_white, small_grid, camera.m_hat, camera.cfa)(small_raw)   # imports, OpenCV start-up
    decoder, prepare_s = bl.time_once(lambda: make_decoder(white, grid, camera.m_hat, camera.cfa,
                                                           interpolation="linear", demosaic_method="fast"))
    copy_floor = bl.measure(lambda: raw.copy(), s.cheap_repeats, memory=False).median_s
    rows, views = [], None
    cases = [(interp, "fast") for interp in INTERPOLATIONS] + [("linear", "careful")]
    for interp, method in cases:
        # the same decoder with another interpolation/demosaic for the capture: the per-capture call is
        # what is timed; make_decoder (the white image's share) is timed once, for linear/fast
        dec = dataclasses.replace(decoder, interpolation=interp, demosaic_method=method)
        timing, result = bl.measure_keeping(lambda: dec(raw), s.repeats)
        rows.append({"interpolation": interp, "demosaic": method, "timing": timing.as_dict(),
                     "mpx_per_s": mpx / timing.median_s, "ratio_to_copy": timing.median_s / copy_floor,
                     "meets_target": timing.median_s <= DECODE_TARGET_S})
        log(f"  decode {interp}/{method}: {timing.median_s:.2f} s (peak {timing.peak_mb:.0f} MB)")
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


def stage_decode_scaling(raw, white, camera, s: Settings, full_row: dict) -> dict:
    """Decode (linear, fast) time against sensor size: central crops of the big capture, exact crop grids."""
    from lfproc.decode import make_decoder

    points = []
    for shape in crop_shapes(raw.shape):
        if tuple(shape) == tuple(raw.shape):
            median = full_row["timing"]["median_s"]
        else:
            where, grid = centre_crop(camera, raw.shape, shape)
            crop_raw, crop_white = np.ascontiguousarray(raw[where]), np.ascontiguousarray(white[where])
            dec = make_decoder(crop_white, grid, camera.m_hat, camera.cfa)
            median = bl.measure(lambda: dec(crop_raw), s.cheap_repeats, memory=False).median_s
        points.append({"sensor_shape": list(shape), "mpx": shape[0] * shape[1] / 1e6, "median_s": median})
        log(f"  decode scaling {shape}: {median:.3f} s")
    fit = bl.power_law_fit([p["mpx"] for p in points], [p["median_s"] for p in points])
    return {"points": points, "fit": fit}


def render_psnr_capture(camera, s: Settings):
    from lfproc import simulate

    tint = (1.0, 0.7, 0.4) if camera.cfa != "none" else (1.0, 1.0, 1.0)
    return simulate.render(camera, noise_scene(camera, 1.0, tint), s.psnr_shape, rotation_deg=0.4,
                           offset_px=(0.3, -0.2), rim_radius_mm=None, pixel_samples=s.psnr_pixel_samples,
                           aperture_samples=s.psnr_aperture_samples, seed=1)


def stage_decode_accuracy(s: Settings) -> dict:
    """PSNR of decoded views against the simulator's ideal views (9 µm pixels, 250 µm lenses, m̂ = 25)."""
    from lfproc.decode import decode, hex_to_rect

    rows = []

    def add(label, sim, interp, method, rings=1):
        cam = sim.camera
        views = decode(normalised(sim.raw, cam), normalised(sim.white, cam), sim.grid, cam.m_hat, cam.cfa,
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
        rows.append({"capture": label, "interpolation": interp, "demosaic": method, "psnr_db": value,
                     "outer_ring_psnr_db": outer_db, "rings_excluded": rings,
                     "meets_target": value >= PSNR_TARGET_DB if interp != "nearest" else None})
        log(f"  PSNR {label} {interp}/{method}: {value:.1f} dB")

    start = time.perf_counter()
    mono = render_psnr_capture(paper_9um_camera(), s)
    for interp in INTERPOLATIONS:
        add("mono, rectangular", mono, interp, "fast")
    bayer = render_psnr_capture(paper_9um_camera("RGGB"), s)
    for method in ("fast", "careful"):
        add("RGGB, rectangular", bayer, "linear", method)
    add("RGGB, rectangular", bayer, "cubic", "careful")
    hexa = render_psnr_capture(paper_9um_camera(grid="hexagonal"), s)
    add("mono, hexagonal", hexa, "linear", "fast")
    # convergence: one more sample per axis must not change the PSNR (the reference is not the limit)
    finer = dataclasses.replace(s, psnr_pixel_samples=s.psnr_pixel_samples + 1,
                                psnr_aperture_samples=s.psnr_aperture_samples + 1)
    add(f"mono, rectangular, {finer.psnr_pixel_samples}²×{finer.psnr_aperture_samples}² samples",
        render_psnr_capture(paper_9um_camera(), finer), "linear", "fast")
    return {"sensor_shape": list(s.psnr_shape), "pixel_samples": s.psnr_pixel_samples,
            "aperture_samples": s.psnr_aperture_samples, "rows": rows,
            "seconds_incl_render": time.perf_counter() - start}


def first_refocus_calls() -> dict:
    """First calls in this process on a tiny light field: numba compile or load from its on-disk cache."""
    from lfproc.refocus import refocus

    tiny = np.ones((3, 3, 4, 5, 3), dtype=np.float32)
    _, gather = bl.time_once(lambda: refocus(tiny, 1.0))
    _, interp = bl.time_once(lambda: refocus(tiny, 0.5))
    return {"first_call_gather_s": gather, "first_call_interpolated_s": interp}


def fresh_compile_seconds() -> dict:
    """The same first calls in a subprocess whose numba cache is empty: the compile time of a fresh install."""
    code = ("import time, numpy as np\n"
            "t = time.perf_counter(); from lfproc.refocus import refocus; imp = time.perf_counter() - t\n"
            "v = np.ones((3, 3, 4, 5, 3), np.float32)\n"
            "t = time.perf_counter(); refocus(v, 1.0); g = time.perf_counter() - t\n"
            "t = time.perf_counter(); refocus(v, 0.5); i = time.perf_counter() - t\n"
            "print(imp, g, i)\n")
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                             cwd=str(ROOT))
    imp, gather, interp = (float(v) for v in out.stdout.split())
    return {"import_s": imp, "compile_gather_s": gather, "compile_interpolated_s": interp}


def stage_refocus(views: np.ndarray, s: Settings, first_calls: dict) -> dict:
    """Refocus timings on the decoded light field, accuracy on a crop and on an analytic plane."""
    from lfproc.refocus import refocus

    gb = views.nbytes / 1e9
    floor = bl.measure(lambda: views.sum(axis=(0, 1)), s.cheap_repeats)
    cases = [("integer a", INTEGER_A, "linear", 1), ("integer a", INTEGER_A, "linear", 2)]
    cases += [("real a", REAL_A, interp, up) for up in (1, 2) for interp in REFOCUS_INTERPOLATIONS]
    ny, nx = s.refocus_accuracy_lenses
    y0, x0 = (views.shape[2] - ny) // 2, (views.shape[3] - nx) // 2
    crop = np.ascontiguousarray(views[:, :, y0:y0 + ny, x0:x0 + nx])
    plane, texture = bl.plane_light_field(views.shape[0], (ny, nx), REAL_A)
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
        log(f"  refocus {label} {interp} x{up}: {timing.median_s:.3f} s, {row['ratio_to_floor']:.2f} x floor")
    scaling = {"slices": list(SLICE_COUNTS), "integer_s": [], "real_linear_s": []}
    for k in SLICE_COUNTS:
        integer = [float((i % 5) - 2) for i in range(k)]        # cycles through −2 … 2
        real = [float(v) for v in np.linspace(-2.0, 2.0, k) + 0.37]   # fractional positions
        scaling["integer_s"].append(bl.measure(lambda: refocus(views, integer), s.cheap_repeats, memory=False).median_s)
        scaling["real_linear_s"].append(bl.measure(lambda: refocus(views, real), s.cheap_repeats, memory=False).median_s)
        log(f"  refocus {k} slices: {scaling['integer_s'][-1]:.3f} s integer, {scaling['real_linear_s'][-1]:.3f} s real")
    scaling["integer_fit"] = bl.power_law_fit(SLICE_COUNTS, scaling["integer_s"])
    scaling["real_linear_fit"] = bl.power_law_fit(SLICE_COUNTS, scaling["real_linear_s"])
    return {"views_shape": list(views.shape), "gb": gb, "floor": floor.as_dict(),
            "floor_gb_per_s": gb / floor.median_s, "rows": rows, "scaling": scaling,
            "accuracy_crop_lenses": [ny, nx], "compile": first_calls}


def stage_views(views: np.ndarray, camera, s: Settings) -> dict:
    """viewpoints (plain and aperture-masked) and the mosaic, against a copy of the views."""
    from lfproc import LightField
    from lfproc.geometry import views_inside_aperture
    from lfproc.viewpoints import mosaic, viewpoints

    lf = LightField.from_views(views, camera)
    gb = views.nbytes / 1e9
    floor = bl.measure(lambda: views.copy(), s.cheap_repeats)
    rows = []
    for label, fn in [("viewpoints(lf)", lambda: viewpoints(lf)),
                      ("viewpoints(lf, inside_aperture=True)", lambda: viewpoints(lf, inside_aperture=True)),
                      ("mosaic(views)", lambda: mosaic(views))]:
        timing = bl.measure(fn, s.cheap_repeats)
        no_copy = label == "viewpoints(lf)"   # returns lf.views itself: a throughput would be meaningless
        rows.append({"case": label, "timing": timing.as_dict(), "gb_per_s": None if no_copy else gb / timing.median_s,
                     "ratio_to_floor": timing.median_s / floor.median_s})
    # exactness: every output is the input's samples, bit for bit
    m, _, ny, nx, _ = views.shape
    inside = views_inside_aperture(camera)
    masked = viewpoints(lf, inside_aperture=True)
    tiles = mosaic(views).reshape(m, ny, m, nx, -1).transpose(0, 2, 1, 3, 4)
    exact = {"viewpoints": bool(np.array_equal(viewpoints(lf), views)),
             "inside_aperture": bool(np.array_equal(masked[inside], views[inside]) and not masked[~inside].any()),
             "mosaic": bool(np.array_equal(tiles, views)), "views_inside_aperture": int(inside.sum()),
             "views_total": int(m * m)}
    return {"views_shape": list(views.shape), "floor": floor.as_dict(), "rows": rows, "exact": exact}


def stage_geometry(s: Settings) -> dict:
    """slice_geometry speed; the model against the paper's tables and its Zemax simulation; thin vs thick lens."""
    from lfproc import Camera
    from lfproc import geometry as g

    f100 = Camera.from_toml(CAMERAS / "paper-f100.toml")
    b20 = Camera.from_toml(CAMERAS / "paper-f100-b20.toml")
    a_values = np.linspace(-1.0, 50.0, GEOMETRY_SAMPLES)
    timing = bl.measure(lambda: g.slice_geometry(f100, a_values), s.cheap_repeats)

    def entries(table):
        """(a, which, table value, model value) of every finite entry; infinite ones must be infinite."""
        found = []
        for a, expected in table.items():
            geo = g.slice_geometry(f100, float(a))
            for which, e, v in zip(("near", "distance", "far"), expected, (geo.near_mm, geo.distance_mm, geo.far_mm)):
                if math.isinf(e):
                    if not math.isinf(v):
                        raise AssertionError(f"Table 2 a={a} {which}: expected infinity, got {v}")
                else:
                    found.append((a, which, e, v))
        return found

    predicted = entries(TABLE2_PREDICTED)
    worst = max(predicted, key=lambda x: abs(x[3] - x[2]))
    without_d0 = max(abs(v - e) for a, which, e, v in predicted if not (a == 0 and which == "near"))
    zemax_err_per_a = {}   # the paper's ERR (Eq. 37): (prediction − simulation)/prediction, largest |ERR| per a
    for a, _, e, v in entries(TABLE2_ZEMAX):
        err = 100 * (v - e) / v
        if abs(err) > abs(zemax_err_per_a.get(a, 0.0)):
            zemax_err_per_a[a] = err
    t4 = []
    for (i, gap), (baseline, tilt1, tilt2) in TABLE4.items():
        pos = g.view_positions_mm(f100, [i, i + gap])
        t4.append({"i": i, "gap": gap, "baseline_err_mm": abs(abs(pos[0] - pos[1]) - baseline),
                   "tilt_b1_err_deg": abs(abs(g.view_tilts_deg(f100, [i])[0]) - tilt1),
                   "tilt_b2_err_deg": abs(abs(g.view_tilts_deg(b20, [i])[0]) - tilt2)})
    thin = dataclasses.replace(f100, mla_principal_plane_gap_mm=0.0, main_principal_plane_gap_mm=0.0)
    a15 = np.arange(1, 6, dtype=float)
    thick_geo, thin_geo = g.slice_geometry(f100, a15), g.slice_geometry(thin, a15)
    thin_rows = [{"a": float(a), "thick_mm": float(d1), "thin_mm": float(d0), "diff_mm": float(d0 - d1),
                  "diff_percent": float(100 * (d0 - d1) / d1), "dof_thick_mm": float(w1), "dof_thin_mm": float(w0)}
                 for a, d1, d0, w1, w0 in zip(a15, thick_geo.distance_mm, thin_geo.distance_mm, thick_geo.dof_mm,
                                              thin_geo.dof_mm)]
    return {"samples": GEOMETRY_SAMPLES, "timing": timing.as_dict(),
            "m_values_per_s": GEOMETRY_SAMPLES / timing.median_s / 1e6,
            "table2_max_abs_err_mm": abs(worst[3] - worst[2]), "table2_worst": f"a={worst[0]} {worst[1]}",
            "table2_max_rel_err": max(abs(v - e) / e for _, _, e, v in predicted),
            "table2_max_abs_err_mm_without_d0_minus": without_d0,
            "table4": t4, "table4_max_baseline_err_mm": max(r["baseline_err_mm"] for r in t4),
            "table4_max_tilt_err_deg": max(max(r["tilt_b1_err_deg"], r["tilt_b2_err_deg"]) for r in t4),
            "vs_zemax_err_percent_per_a": {str(a): v for a, v in zemax_err_per_a.items()},
            "thin_vs_thick": thin_rows}


# ============================================================================ report
def _t(timing: dict) -> str:
    return f"{bl.fmt(timing['median_s'])} ({bl.fmt(timing['min_s'])})"


def _mb(timing: dict) -> str:
    return bl.fmt(timing.get("peak_mb"), 2 if (timing.get("peak_mb") or 0) < 10 else 3)


#: the stages measured by their own scripts (each page says how it was made); listed at the top of this page
STAGE_PAGES = [
    "Stages with their own benchmark script and page: [calibration](benchmarks-calibrate.md) "
    "(`scripts/bench_calibrate.py`), [decoding: bias, colour, memory](benchmarks-decode.md) "
    "(`scripts/bench_decode.py`), [Lytro unpacking](benchmarks-lytro.md) (`scripts/bench_lytro.py`), "
    "[geometry and triangulation](benchmarks-geometry.md) (`scripts/bench_geometry.py`), "
    "[depth maps](benchmarks-depth.md) (`scripts/bench_depth.py`), [the viewer](benchmarks-viewer.md) "
    "(`scripts/bench_viewer.py`), [whole commands: time, peak memory, view writing against the disk]"
    "(benchmarks-commands.md) (`scripts/bench_commands.py`), [refocusing](../README.md#refocusing-speed) "
    "(`scripts/bench_refocus.py`). The tables below (`scripts/bench.py`) predate this wave's calibration "
    "and decoding changes where those pages give newer numbers. Their headline numbers (Illum-sized "
    "inputs, 2 cores, 2026-11-23; each page has the method, the load and the floor of its run):",
    "",
    "| stage | measured | floor or baseline in the same run | target |",
    "| --- | --- | --- | --- |",
    "| unpack a 7728 × 5368 10-bit Illum raw | 0.28 s | `numpy.fromfile` of the bytes 0.048 s; straightforward "
    "numpy 2.4 s | ≤ 0.5 s |",
    "| `lfproc calibrate`, 41 Mpx white | 2.6 s CPU, 0.34 GB peak | one FFT of the image 0.84 s CPU; previous code "
    "40 s, 2.96 GB | ≤ 3 s, ≤ 1.5 GB |",
    "| `lfproc refocus` / `views`, whole command | 2.1 / 2.0 GB peak | previous code 3.22 / 3.15 GB | ≤ 2.5 GB |",
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

    # ---------------------------------------------------------------- read
    rd = r["read"]
    out += ["## Read (`lfproc.io.read_capture`)", "",
            f"Raw of {rd['sensor_shape'][1]} × {rd['sensor_shape'][0]} px, 16-bit. Floor: OpenImageIO's own "
            f"read of the same file as uint16 (no conversion). Reading the uncompressed TIFF's bytes with "
            f"`numpy.fromfile` (page cache) takes {bl.fmt(rd['fromfile_tiff_s'])} s "
            f"({rd['fromfile_tiff_mb_per_s']:.0f} MB/s). Accuracy: largest difference from "
            f"(DN − black)/(white − black) computed in float64.", "",
            bl.markdown_table(["case", "file MB", "time s (min)", "Mpx/s", "file MB/s", "× floor", "peak MB",
                               "max abs error"],
                              [[x["case"], x["file_mb"], _t(x["timing"]), x["mpx_per_s"], x["file_mb_per_s"],
                                x["ratio_to_floor"], _mb(x["timing"]), x["max_abs_error"]] for x in rd["rows"]]), ""]

    # ---------------------------------------------------------------- calibrate
    cal = r["calibrate"]
    out += ["## Calibrate (`lfproc.calibrate.estimate_grid`)", "",
            "White images of the capture above (central crops of it, with their exact grids), hexagonal lattice rotated by "
            f"{LYTRO_ROTATION_DEG}°, pitch 14.29 px. Centre RMS: distance of every true lens centre from the "
            "nearest fitted lattice point (targets ≤ 0.05 px, pitch ≤ 0.005 px, rotation ≤ 0.01°). No floor.", "",
            bl.markdown_table(["sensor px", "lenses", "runs", "time s (min)", "Mpx/s", "peak MB", "centre RMS px",
                               "pitch err px", "rotation err °", "fit residual px"],
                              [[f"{x['sensor_shape'][1]} × {x['sensor_shape'][0]}", str(x["lenses"]), x["runs"],
                                _t(x["timing"]), x["mpx_per_s"], _mb(x["timing"]), x["centre_rms_px"],
                                x["pitch_error_px"], x["rotation_error_deg"], x["residual_rms_px"]]
                               for x in cal["rows"]]), "",
            "*Fit residual* is the scatter of the individually measured centres about the fitted lattice. The "
            "speed capture's white image has one ray per pixel (aliased micro-image edges), which scatters single "
            "centres; the last row is a white image rendered with 2²×3² samples per pixel. The lattice itself "
            "(centre RMS) is accurate either way.", ""]

    # ---------------------------------------------------------------- decode
    dec, acc, sc = r["decode"], r["decode_accuracy"], r["decode_scaling"]
    comp = dec["components"]
    out += ["## Decode (`lfproc.decode.make_decoder` + call)", "",
            f"Speed on the {dec['sensor_shape'][1]} × {dec['sensor_shape'][0]} px capture ({dec['mpx']:.1f} Mpx, "
            f"{dec['lens_grid'][0]} × {dec['lens_grid'][1]} hexagonal lenses → views "
            f"{' × '.join(str(v) for v in dec['views_shape'])} float32 = {dec['views_gb']:.2f} GB). Target ≤ "
            f"{DECODE_TARGET_S:g} s. `make_decoder` (demosaic and resample the white image, once per white "
            f"image) took {dec['prepare_s']:.2f} s for linear/fast; the table times the per-capture call. "
            f"Floors: a numpy copy of the sensor ({bl.fmt(dec['copy_floor_s'])} s) and `cv2.remap` alone with the "
            f"decoder's float32 maps on the demosaiced image, same interpolation.", "",
            bl.markdown_table(["interpolation", "demosaic", "time s (min)", "Mpx/s", "× remap floor", "× copy",
                               "peak MB", f"≤ {DECODE_TARGET_S:g} s (median / fastest)"],
                              [[x["interpolation"], x["demosaic"], _t(x["timing"]), x["mpx_per_s"],
                                x.get("ratio_to_remap"), x["ratio_to_copy"], _mb(x["timing"]),
                                ("yes" if x["meets_target"] else "no") + " / "
                                + ("yes" if x["timing"]["min_s"] <= DECODE_TARGET_S else "no")]
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
            f"more sample per axis: the reference has converged when it barely moves. Target ≥ {PSNR_TARGET_DB:g} dB (linear).", "",
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

    # ---------------------------------------------------------------- refocus
    rf = r["refocus"]
    comp_r = rf["compile"]
    out += ["## Refocus (`lfproc.refocus`)", "",
            f"Light field: the decoded views above, {' × '.join(str(v) for v in rf['views_shape'])} float32 "
            f"({rf['gb']:.2f} GB). Floor: `views.sum(axis=(0, 1))`, {bl.fmt(rf['floor']['median_s'])} s "
            f"({rf['floor_gb_per_s']:.1f} GB/s), one read of the data. Integer a = {INTEGER_A:g}, real a = "
            f"{REAL_A}. Accuracy: (1) against a plain float64 numpy implementation of the contract's formula "
            f"(`benchlib.refocus_reference`) on a {rf['accuracy_crop_lenses'][0]} × {rf['accuracy_crop_lenses'][1]}-lens "
            f"crop: the float32 arithmetic's error; (2) *plane PSNR*: a light field of one textured plane at "
            f"disparity a = {REAL_A} (two sinusoids below 0.2 cycles per lens) refocused at that a against the "
            f"texture itself: the interpolation's error.", "",
            bl.markdown_table(["case", "interpolation", "upsample", "time s (min)", "GB/s", "× floor", "peak MB",
                               "max rel. err vs float64", "plane PSNR dB"],
                              [[x["case"], x["interpolation"], str(x["upsample"]), _t(x["timing"]), x["gb_per_s"],
                                x["ratio_to_floor"], _mb(x["timing"]), x["max_rel_error_vs_float64"],
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

    # ---------------------------------------------------------------- views
    vw = r["views"]
    ex = vw["exact"]
    out += ["## Views (`lfproc.viewpoints`)", "",
            f"Same light field. Floor: `views.copy()`, {bl.fmt(vw['floor']['median_s'])} s. `viewpoints(lf)` "
            "returns the decoded array itself (Eq. 32 is the layout), so it costs nothing.", "",
            bl.markdown_table(["case", "time s (min)", "GB/s", "× floor", "peak MB"],
                              [[x["case"], _t(x["timing"]), x["gb_per_s"], x["ratio_to_floor"], _mb(x["timing"])]
                               for x in vw["rows"]]), "",
            f"Accuracy: exact by construction and checked bit for bit — viewpoints {ex['viewpoints']}, aperture mask "
            f"{ex['inside_aperture']} ({ex['views_inside_aperture']} of {ex['views_total']} views inside the f/2 "
            f"stop), mosaic {ex['mosaic']}.", ""]

    # ---------------------------------------------------------------- geometry
    ge = r["geometry"]
    out += ["## Geometry (`lfproc.geometry.slice_geometry`)", "",
            f"{ge['samples']:,} values of a in one call: {_t(ge['timing'])} s, "
            f"{ge['m_values_per_s']:.1f} M slices/s, peak {_mb(ge['timing'])} MB.", "",
            bl.markdown_table(["check", "result"], [
                ["Table 2 (f100): largest error against the paper's prediction",
                 f"{bl.fmt(ge['table2_max_abs_err_mm'])} mm at {ge['table2_worst']} "
                 f"(relative {bl.fmt(ge['table2_max_rel_err'])}); without d₀₋: "
                 f"{bl.fmt(ge['table2_max_abs_err_mm_without_d0_minus'])} mm"],
                ["Table 4, largest baseline error", f"{bl.fmt(ge['table4_max_baseline_err_mm'])} mm"],
                ["Table 4, largest tilt error (magnitudes)", f"{bl.fmt(ge['table4_max_tilt_err_deg'])}°"],
                ["Model vs the paper's Zemax ray trace: largest ERR (Eq. 37) of d₋, d, d₊ per a",
                 ", ".join(f"a={a}: {v:+.2f} %" for a, v in ge["vs_zemax_err_percent_per_a"].items())],
            ]), "",
            "d₀₋ sits where the distance moves by −1600 mm per mm of f_s, so the published 3-decimal inputs only "
            "pin it to ~0.07 mm (see tests/test_geometry.py). The model is paraxial: against real (Zemax) optics "
            "it is within 0.5 % at 0.2–0.3 m and 11 % off at 3.5 m (Section 5.2).", "",
            "Thin-lens against thick-lens model: the paper's f100 camera with both principal-plane gaps set to 0 "
            "(H1s–H2s = 0.374 mm, H1U–H2U = −33.184 mm in the real one).", "",
            bl.markdown_table(["a", "thick d_a mm", "thin d_a mm", "thin − thick mm", "%", "DOF thick mm",
                               "DOF thin mm"],
                              [[bl.fmt(x["a"]), x["thick_mm"], x["thin_mm"], x["diff_mm"], x["diff_percent"],
                                x["dof_thick_mm"], x["dof_thin_mm"]] for x in ge["thin_vs_thick"]]), ""]

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
    mono = {i: psnr[("mono, rectangular", i, "fast")] for i in INTERPOLATIONS}
    lin = by[("linear", "fast")]
    t_lin, min_lin = lin["timing"]["median_s"], lin["timing"]["min_s"]
    lines = [
        f"Decode: linear takes {t_lin:.2f} s per {dec['mpx']:.0f} Mpx capture (fastest run {min_lin:.2f} s; target "
        f"{DECODE_TARGET_S:g} s: {'met' if lin['meets_target'] else 'missed'} by the median, "
        f"{'met' if min_lin <= DECODE_TARGET_S else 'missed'} by the fastest run) and reaches {mono['linear']:.1f} dB. "
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
    real = {i: rows[("real a", i, 1)] for i in REFOCUS_INTERPOLATIONS}
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


# ============================================================================ driver
def camera_description(camera, big_shape) -> str:
    return (f"Speed is measured on a simulated Lytro-Illum-like capture: {big_shape[1]} × {big_shape[0]} px sensor, "
            f"{camera.pixel_pitch_mm * 1000:g} µm pixels, {camera.mla_pitch_mm * 1000:g} µm hexagonal micro lenses "
            f"({camera.pitch_px:.2f} px, rotated {LYTRO_ROTATION_DEG}°), {camera.cfa} Bayer mosaic, f/"
            f"{camera.f_number:g}, decoded to m̂ = {camera.m_hat} (one pixel-area sample and one aperture sample per "
            f"pixel: its content does not change the timings). Accuracy is measured on smaller captures with exact "
            f"references, described per stage.")


def run(s: Settings) -> dict:
    from lfproc import simulate

    start = time.perf_counter()
    machine = bl.machine_info()
    results = {"settings": dataclasses.asdict(s), "machine": machine}
    stage_s = results["stage_seconds"] = {}
    first_calls = first_refocus_calls()   # before anything else touches the numba kernels
    if s.fresh_compile:
        log("numba compile time in a fresh process")
        first_calls.update(fresh_compile_seconds())

    camera = lytro_camera()
    log(f"render {s.big_shape} capture")   # setup, not a benchmarked stage
    sim, render_s = bl.time_once(lambda: simulate.render(
        camera, noise_scene(camera, 0.5, (1.0, 0.7, 0.4)), s.big_shape, rotation_deg=LYTRO_ROTATION_DEG,
        offset_px=LYTRO_OFFSET_PX, rim_radius_mm=None, pixel_samples=1, aperture_samples=1, ideal_views=False,
        seed=1))
    results["camera"] = {"description": camera_description(camera, s.big_shape), "render_s": render_s,
                         "toml": camera.to_toml()}
    raw, white = normalised(sim.raw, camera), normalised(sim.white, camera)

    def stage(name, fn):
        log(name)
        value, stage_s[name] = bl.time_once(fn)
        return value

    with tempfile.TemporaryDirectory() as tmp:
        results["read"] = stage("read", lambda: stage_read(sim.raw, camera, s, tmp))
    results["calibrate"] = stage("calibrate", lambda: stage_calibrate(white, camera, s))
    results["decode"], views = stage("decode", lambda: stage_decode_speed(raw, white, sim.grid, camera, s))
    full_row = next(x for x in results["decode"]["rows"] if x["interpolation"] == "linear" and x["demosaic"] == "fast")
    results["decode_scaling"] = stage("decode_scaling", lambda: stage_decode_scaling(raw, white, camera, s, full_row))
    raw = white = sim = None   # free the sensor images before the accuracy renders
    results["decode_accuracy"] = stage("decode_accuracy", lambda: stage_decode_accuracy(s))
    results["refocus"] = stage("refocus", lambda: stage_refocus(views, s, first_calls))
    results["views"] = stage("views", lambda: stage_views(views, camera, s))
    results["geometry"] = stage("geometry", lambda: stage_geometry(s))
    machine["load_average_end"] = list(os.getloadavg())
    results["peak_rss_gb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6   # kB on Linux
    results["total_s"] = time.perf_counter() - start
    return results


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
    s = settings_for(args.quick, args.repeats)
    out_dir = args.out_dir or (Path(tempfile.gettempdir()) / "lfproc-bench-quick" if s.quick else ROOT / "docs")
    results = run(s)
    write_outputs(results, out_dir)
    log(f"done in {results['total_s']:.0f} s; wrote {out_dir / 'benchmarks.md'}, .json and .png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
