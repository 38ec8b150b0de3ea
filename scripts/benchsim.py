"""The simulated cameras, captures and settings that the stages of ``scripts/bench.py`` share.

The Lytro-Illum-like capture every speed measurement runs on, the paper's 9 µm camera of the accuracy
captures, the constants of the suite (interpolations, the a values, targets, the paper's tables) and the
quick/full settings. Each stage's own code lives in its script (``bench_read.py``, ``bench_calibrate.py``,
``bench_decode.py``, ``bench_refocus.py``, ``bench_views.py``, ``bench_geometry.py``); ``bench.py`` runs them.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
from lfproc.camera import MainLens

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

    return Camera(0.0014, 0.02, 0.04, MainLens(50.0, 50.0, f_number=2.0), grid="hexagonal", cfa="GRBG", black_level=64.0, white_level=1023.0, micro_image_px=15, name="lytro-illum-like")


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
    feature = 4 * camera.mla_pitch_mm * (d - camera.main_optics.sensor_path_mm(camera.mla_path_mm)) / camera.main_optics.focal_length_mm
    return Scene((Plane(d, Noise(feature_mm=feature, seed=1), tint=tint),), background=0.1)


def normalised(dn: np.ndarray, camera) -> np.ndarray:
    """16-bit DN to the linear float32 that ``read_capture`` returns."""
    black, white = camera.raw_levels(65535.0)   # the simulator's 16-bit DN; a camera without a white level: 65535
    return (dn.astype(np.float32) - np.float32(black)) / np.float32(white - black)


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


def camera_description(camera, big_shape) -> str:
    return (f"Speed is measured on a simulated Lytro-Illum-like capture: {big_shape[1]} × {big_shape[0]} px sensor, "
            f"{camera.pixel_pitch_mm * 1000:g} µm pixels, {camera.mla_pitch_mm * 1000:g} µm hexagonal micro lenses "
            f"({camera.pitch_px:.2f} px, rotated {LYTRO_ROTATION_DEG}°), {camera.cfa} Bayer mosaic, f/"
            f"{camera.main_optics.f_number:g}, decoded to m̂ = {camera.m_hat} (one pixel-area sample and one aperture sample per "
            f"pixel: its content does not change the timings). Accuracy is measured on smaller captures with exact "
            f"references, described per stage.")


def big_capture(s: Settings) -> dict:
    """The Lytro-sized capture of this run (rendered, one sample per pixel): the simulation, its camera,
    the linear raw and white images and the seconds the render took."""
    from lfproc import simulate

    camera = lytro_camera()
    log(f"render {s.big_shape} capture")   # setup, not a benchmarked stage
    start = time.perf_counter()
    sim = simulate.render(camera, noise_scene(camera, 0.5, (1.0, 0.7, 0.4)), s.big_shape,
                          rotation_deg=LYTRO_ROTATION_DEG, offset_px=LYTRO_OFFSET_PX, rim_radius_mm=None,
                          pixel_samples=1, aperture_samples=1, ideal_views=False, seed=1)
    return {"sim": sim, "camera": camera, "raw": normalised(sim.raw, camera), "white": normalised(sim.white, camera),
            "render_s": time.perf_counter() - start}


def run_stage_alone(description: str, measure, section, argv=None) -> int:
    """A stage script run on its own: ``--quick`` picks the small capture; ``measure(settings, capture)``
    gives the stage's results (keyed as in ``bench.py``), whose section of the page is printed."""
    import argparse

    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--quick", action="store_true", help="the small capture of bench.py --quick")
    args = parser.parse_args(argv)
    s = settings_for(args.quick, None)
    print("\n".join(section(measure(s, big_capture(s)))))
    return 0
