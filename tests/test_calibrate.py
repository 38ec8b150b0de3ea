"""Micro lens grid calibration (`lfproc.calibrate`, `lfproc calibrate`) on simulated white images.

The white images come from tests/whitegen.py, a brute-force renderer independent of lfproc.simulate, with
the true lens centres known exactly. Targets (for the fitted lattice against the true one, over the true
centres): centre RMS <= 0.05 px, rotation within 0.01 deg, pitch within 0.005 px.
"""

import functools
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import ndimage
from scipy.spatial import cKDTree

from conftest import assert_clean_error, run_cli
from lfproc import LfprocError
from lfproc.calibrate import (Similarity, estimate_grid, find_grid, grid_from_fit, lattice_index,
                              refine_centres, repair_outlier_pixels, smooth_large, unit_coordinates)
from lfproc.grid import LensGrid
from whitegen import covering_grid, nearest_lattice_distance, true_centres_inside, white_image

PAPER_PITCH_PX = 0.25 / 0.009  # the paper's 250 um lenses on 9 um pixels: 27.777... px


# ----------------------------------------------------------------------------- helpers
def lattice_errors(fitted: LensGrid, true: LensGrid, shape):
    """(centre RMS, pitch error, rotation error) of the fitted lattice over the true centres in the image.

    Each true centre is compared with the nearest point of the fitted lattice, extended by 10 lenses on
    every side (an even row shift keeps the hexagonal parity).
    """
    extended = LensGrid(fitted.kind, fitted.pitch_px, fitted.rotation_deg, tuple(fitted.lens_xy(-10, -10)),
                        fitted.rows + 20, fitted.cols + 20)
    truth = true_centres_inside(true, shape, 0.5 * true.pitch_px)
    dist, _ = cKDTree(extended.centers_xy_px().reshape(-1, 2)).query(truth)
    return (float(np.sqrt(np.mean(dist ** 2))), fitted.pitch_px - true.pitch_px,
            fitted.rotation_deg - true.rotation_deg)


def assert_targets(fitted: LensGrid, true: LensGrid, shape):
    rms, dpitch, drot = lattice_errors(fitted, true, shape)
    assert fitted.kind == true.kind
    assert rms <= 0.05, rms
    assert abs(dpitch) <= 0.005, dpitch
    assert abs(drot) <= 0.01, drot
    assert 0.0 <= fitted.residual_rms_px <= 0.05


CASES = {
    # name: (shape, kind, pitch, rotation_deg, offset_xy, disk radius / pitch, white_image options)
    "paper-rect": ((330, 420), "rectangular", PAPER_PITCH_PX, 0.3, (0.37, -0.21), 0.45, dict(noise_sigma=0.01)),
    "paper-hex-vignetted": ((360, 440), "hexagonal", PAPER_PITCH_PX, -1.2, (0.11, 0.43), 0.45,
                            dict(vignetting=0.5, cut_radius_px=200.0, noise_sigma=0.01, hot_pixels=12)),
    "small-rect": ((170, 220), "rectangular", 7.5, -1.2, (0.25, 0.1), 0.45, dict(noise_sigma=0.02)),
    "small-hex": ((170, 220), "hexagonal", 7.5, 0.3, (-0.3, 0.2), 0.42, dict(noise_sigma=0.01, vignetting=0.3)),
    "large-rect": ((560, 640), "rectangular", 101.3, 0.3, (0.4, -0.3), 0.45, dict(noise_sigma=0.01, vignetting=0.3)),
    "fat-rect-cells": ((330, 420), "rectangular", 25.3, -0.8, (0.3, 0.0), 0.6, dict(noise_sigma=0.01)),
    "fat-hex-cells": ((330, 420), "hexagonal", 19.7, 0.6, (0.0, 0.3), 0.52, dict(noise_sigma=0.01)),
}


@functools.lru_cache(maxsize=None)
def case(name):
    shape, kind, pitch, rotation, offset, radius, options = CASES[name]
    grid = covering_grid(shape, kind, pitch, rotation, offset)
    supersample = 4 if pitch < 60 else 2
    return white_image(shape, grid, radius * pitch, supersample=supersample, seed=7, **options), grid


# ----------------------------------------------------------------------------- the test data itself
def test_whitegen_nearest_lattice_distance_is_brute_force_nearest():
    for kind in ("rectangular", "hexagonal"):
        grid = covering_grid((60, 80), kind, 10.3, 7.0, (0.3, -0.2))
        points = np.random.default_rng(1).uniform(0, 80, (3000, 2))
        brute, _ = cKDTree(grid.centers_xy_px().reshape(-1, 2)).query(points)
        np.testing.assert_allclose(nearest_lattice_distance(points[:, 0], points[:, 1], grid), brute, atol=1e-9)


def test_whitegen_disks_have_their_area():
    grid = covering_grid((200, 240), "rectangular", 20.0, 0.0)
    image = white_image((200, 240), grid, 8.0, peak=1000.0, supersample=8)
    # a whole number of cells (10 x 12 lenses of 20 px): lit fraction = disk area / cell area
    assert image.mean() / 1000.0 == pytest.approx(math.pi * 8.0 ** 2 / 20.0 ** 2, rel=2e-3)


# ----------------------------------------------------------------------------- accuracy targets
@pytest.mark.parametrize("name", list(CASES))
def test_fitted_lattice_meets_the_targets(name):
    image, true = case(name)
    kind = true.kind if name.startswith("paper") else None  # camera file kind, or auto-detection
    fitted = estimate_grid(image, kind=kind, approx_pitch_px=true.pitch_px * 1.02)
    assert_targets(fitted, true, image.shape)


@pytest.mark.parametrize("name", ["paper-rect", "paper-hex-vignetted", "small-hex"])
def test_grid_covers_every_lens_on_the_sensor_in_the_lensgrid_convention(name):
    image, true = case(name)
    fitted = estimate_grid(image)
    centres = fitted.centers_xy_px().reshape(-1, 2)
    # every true lens whose cell lies on the sensor (and is lit) is one of the grid's rows x cols lenses
    truth = true_centres_inside(true, image.shape, 0.5 * true.pitch_px + 1.0)
    if name == "paper-hex-vignetted":  # lenses beyond the mechanical vignetting cut are dark: not found
        h, w = image.shape
        truth = truth[np.hypot(truth[:, 0] - (w - 1) / 2, truth[:, 1] - (h - 1) / 2) < 200.0 - true.pitch_px]
    dist, _ = cKDTree(centres).query(truth)
    assert dist.max() < 0.1
    # and the index rectangle is no larger than needed: its first and last rows and columns hold a lens
    # whose centre is on the sensor
    xy = fitted.centers_xy_px()
    h, w = image.shape
    on = (xy[..., 0] >= 0) & (xy[..., 0] <= w - 1) & (xy[..., 1] >= 0) & (xy[..., 1] <= h - 1)
    assert on[0].any() and on[-1].any() and on[:, 0].any() and on[:, -1].any()


def test_find_grid_reports_measured_centres_close_to_the_truth():
    image, true = case("paper-rect")
    estimate = find_grid(image)
    used = estimate.centers_xy_px[estimate.inlier]
    assert len(used) >= 100
    dist, _ = cKDTree(true.centers_xy_px().reshape(-1, 2)).query(used)
    assert np.sqrt(np.mean(dist ** 2)) < 0.03
    assert estimate.grid.residual_rms_px == pytest.approx(np.sqrt(np.mean(dist ** 2)), abs=0.01)


def test_black_level_offset_is_removed_with_the_floor():
    image, true = case("paper-rect")
    offset = image.astype(np.float64) + 4000.0
    assert_targets(estimate_grid(offset), true, image.shape)


def test_bayer_mosaic_and_rgb_inputs():
    image, true = case("paper-rect")
    gains = np.array([[0.45, 1.0], [1.0, 0.7]])  # RGGB white balance of a white surface
    h, w = image.shape
    mosaic = image * np.tile(gains, (h // 2, w // 2))
    assert_targets(estimate_grid(mosaic, cfa="RGGB"), true, image.shape)
    rgb = (image[..., None] * np.array([0.45, 1.0, 0.7]) / 65535.0).astype(np.float32)
    assert_targets(estimate_grid(rgb), true, image.shape)


def test_large_pitch_150px():
    shape = (1000, 1150)
    true = covering_grid(shape, "hexagonal", 150.0, -0.7, (0.2, 0.3))
    image = white_image(shape, true, 0.45 * 150.0, noise_sigma=0.01, vignetting=0.3, supersample=2, seed=3)
    assert_targets(estimate_grid(image, "hexagonal", 150.0), true, shape)


# ----------------------------------------------------------------------------- pieces
def test_symmetry_centre_is_unbiased_under_a_brightness_slope():
    # one disk under a steep linear ramp: the centroid would move, the symmetry centre with slope must not
    grid = LensGrid("rectangular", 60.0, 0.0, (40.3, 39.6), 1, 1)
    disk = white_image((80, 80), grid, 20.0, peak=60000.0, supersample=8).astype(np.float64) / 60000.0
    ramp = 1.0 + 0.01 * (np.arange(80)[None, :] - 40.0)  # 40 % brighter on the right
    sigma = 3.0
    smooth = ndimage.gaussian_filter(disk * ramp, sigma)
    start = np.array([[41.0, 39.0]])
    corrected, asym = refine_centres(smooth, start, 60.0, blur_variance=sigma ** 2 + 1 / 12)
    uncorrected, _ = refine_centres(smooth, start, 60.0, blur_variance=0.0)
    truth = np.array(grid.origin_xy_px)
    assert np.hypot(*(corrected[0] - truth)) < 0.01
    assert np.hypot(*(uncorrected[0] - truth)) > 0.05  # the sigma^2 g correction matters
    ys, xs = np.nonzero(disk > 0)
    weights = (disk * ramp)[ys, xs]
    assert abs(np.sum(xs * weights) / weights.sum() - truth[0]) > 0.5  # a plain centroid is far off
    assert asym[0] < 1e-3


def test_outlier_pixels_are_repaired_and_clean_images_untouched():
    image, _ = case("small-rect")
    clean = image.astype(np.float64)
    assert np.array_equal(repair_outlier_pixels(clean), clean)
    hot = clean.copy()
    spots = (np.array([40, 90, 120]), np.array([33, 150, 7]))
    hot[spots] = 65535.0
    bright = ndimage.minimum_filter(clean, size=3) > 0.8 * clean.max()
    lit = np.argwhere(bright[5:-5, 5:-5])[0] + 5  # inside a micro image, away from the border
    hot[tuple(lit)] = 0.0  # a dead pixel
    repaired = repair_outlier_pixels(hot)
    ring = np.ones((3, 3), bool)
    ring[1, 1] = False
    assert np.all(repaired[spots] <= ndimage.maximum_filter(clean, footprint=ring)[spots])
    assert repaired[tuple(lit)] >= 0.8 * clean.max()
    assert np.count_nonzero(repaired != hot) == 4


def test_smooth_large_matches_gaussian_filter():
    field = ndimage.gaussian_filter(np.random.default_rng(2).normal(size=(300, 360)), 6.0)
    field += np.linspace(0, 1, 360)[None, :]
    sigma = 30.0
    reference = ndimage.gaussian_filter(field, sigma)
    assert np.abs(smooth_large(field, sigma) - reference)[40:-40, 40:-40].max() < 0.01 * np.ptp(reference)


@settings(max_examples=60, deadline=None)
@given(kind=st.sampled_from(["rectangular", "hexagonal"]), pitch=st.floats(5.0, 200.0),
       rotation=st.floats(-44.0, 44.0), ox=st.floats(-500, 500), oy=st.floats(-500, 500),
       i0=st.integers(-7, 7), j0=st.integers(-7, 7), ni=st.integers(1, 6), nj=st.integers(1, 6))
def test_grid_from_fit_reproduces_the_fitted_lattice(kind, pitch, rotation, ox, oy, i0, j0, ni, nj):
    theta = math.radians(rotation)
    model = Similarity(np.array([ox, oy]), pitch * math.cos(theta), pitch * math.sin(theta))
    ii, jj = np.meshgrid(np.arange(i0, i0 + ni), np.arange(j0, j0 + nj))
    index = np.stack([ii.ravel(), jj.ravel()], -1).astype(float)
    xy = model.xy(unit_coordinates(kind, index))
    assert np.array_equal(lattice_index(kind, model.st(xy)), index)
    grid = grid_from_fit(kind, model, index, (1, 1), 0.0)  # a 1-pixel sensor: no cell on it, all kept
    assert grid.rows == nj and grid.pitch_px == pytest.approx(pitch) and grid.rotation_deg == pytest.approx(rotation)
    grid_xy = grid.centers_xy_px().reshape(-1, 2)
    dist, _ = cKDTree(grid_xy).query(xy)
    assert dist.max() < 1e-6 * max(pitch, abs(ox), abs(oy))  # every lens is a grid lens
    if kind == "rectangular":
        assert grid.cols == ni
    else:  # indices (i, j) with fixed i slant by half a lens per row: more grid columns cover them
        assert ni <= grid.cols <= ni + (nj + 1) // 2


# ----------------------------------------------------------------------------- errors
@pytest.mark.parametrize("what", ["flat", "black", "noise", "vignetted-flat"])
def test_images_without_a_grid_are_refused(what):
    rng = np.random.default_rng(0)
    shape = (240, 300)
    images = {
        "flat": np.full(shape, 30000, np.uint16),
        "black": np.zeros(shape, np.uint16),
        "noise": rng.normal(30000, 3000, shape).clip(0, 65535).astype(np.uint16),
        "vignetted-flat": (50000 * (1 - 0.5 * np.linspace(-1, 1, shape[1]) ** 2))[None, :].repeat(shape[0], 0),
    }
    with pytest.raises(LfprocError, match="no micro lens grid found") as info:
        estimate_grid(images[what], approx_pitch_px=PAPER_PITCH_PX if what == "noise" else None)
    assert "\n" not in str(info.value)


def test_pitch_mismatch_with_the_camera_is_refused():
    image, true = case("paper-rect")
    estimate_grid(image, approx_pitch_px=true.pitch_px * 1.045)  # within 5 %: fine
    for wrong in (true.pitch_px * 1.06, true.pitch_px / 1.06, true.pitch_px * 2, 25.0):
        with pytest.raises(LfprocError, match="does not match the white image"):
            estimate_grid(image, approx_pitch_px=wrong)


def test_kind_mismatch_and_bad_inputs_are_refused():
    image, _ = case("paper-rect")
    with pytest.raises(LfprocError, match="mla.grid"):
        estimate_grid(image, kind="hexagonal")
    with pytest.raises(LfprocError, match="unknown grid kind"):
        estimate_grid(image, kind="square")
    bad = image.astype(np.float64)
    bad[10, 10] = np.nan
    with pytest.raises(LfprocError, match="NaN"):
        estimate_grid(bad)
    with pytest.raises(LfprocError, match="2-D image"):
        estimate_grid(np.zeros(5))


# ----------------------------------------------------------------------------- command line
CAMERA_TOML = """
[sensor]
pixel_pitch_mm = 0.009
[mla]
pitch_mm = {pitch_mm}
focal_length_mm = 2.749
grid = "{grid}"
[main_lens]
focal_length_mm = 99.5145
image_distance_mm = 99.5145
"""


def test_cli_writes_the_contract_grid_json_and_plot(tmp_path):
    import tifffile
    image, true = case("paper-hex-vignetted")
    white = tmp_path / "white.tif"
    tifffile.imwrite(white, image)
    camera = tmp_path / "cam.toml"
    camera.write_text(CAMERA_TOML.format(pitch_mm=0.25, grid="hexagonal"))
    out, plot = tmp_path / "out" / "grid.json", tmp_path / "fit.png"
    proc = run_cli("calibrate", white, "--camera", camera, "-o", out, "--plot", plot)
    assert proc.returncode == 0, proc.stderr
    text = out.read_text()
    data = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-strict JSON constant {c}"))
    assert data["grid"] == "hexagonal"
    fitted = LensGrid.from_json_dict(data)
    assert_targets(fitted, true, image.shape)
    assert data["pitch_px"] == fitted.pitch_px and data["rotation_deg"] == fitted.rotation_deg
    assert 0 < data["residual_rms_px"] < 0.05
    centres = np.array(data["centers_xy_px"])
    assert centres.shape == (fitted.rows * fitted.cols, 2)
    np.testing.assert_allclose(centres, fitted.centers_xy_px().reshape(-1, 2))
    assert data["white_image"] == str(white.resolve())
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "hexagonal grid" in proc.stdout


def test_cli_refuses_a_camera_whose_pitch_does_not_match(tmp_path):
    import tifffile
    image, _ = case("paper-rect")
    white = tmp_path / "white.tif"
    tifffile.imwrite(white, image)
    camera = tmp_path / "cam.toml"
    camera.write_text(CAMERA_TOML.format(pitch_mm=0.3, grid="rectangular"))
    out = tmp_path / "grid.json"
    proc = run_cli("calibrate", white, "--camera", camera, "-o", out)
    assert_clean_error(proc, "does not match the white image", str(white))
    assert set(tmp_path.iterdir()) == {white, camera}  # nothing written, not even a temporary file
