"""Decoding against independent references: a plain reshape, analytic images, and linear fields."""

import math

import numpy as np
import pytest

from lfproc import LfprocError, LensGrid
from lfproc.decode import decode, demosaic, hex_to_rect, make_decoder, sample_positions


def aligned_grid(m, rows, cols):
    c = (m - 1) // 2
    return LensGrid("rectangular", float(m), 0.0, (c, c), rows, cols)


@pytest.mark.parametrize("m", [1, 3, 7])
@pytest.mark.parametrize("interpolation", ["nearest", "linear", "cubic", "lanczos"])
def test_aligned_integer_pitch_is_a_plain_reshape(m, interpolation):
    rows, cols = 4, 5
    rng = np.random.default_rng(m)
    sensor = rng.random((rows * m, cols * m)).astype(np.float32)
    views = decode(sensor, np.ones_like(sensor), aligned_grid(m, rows, cols), m, interpolation=interpolation)
    # independent reference: micro image (r, q) is sensor[r*m:(r+1)*m, q*m:(q+1)*m]; its pixel (ky, kx) is view (ky, kx)
    ref = sensor.reshape(rows, m, cols, m).transpose(1, 3, 0, 2)[..., None]
    assert views.shape == (m, m, rows, cols, 1) and views.dtype == np.float32
    inner = (slice(None), slice(None), slice(1, -1), slice(1, -1))  # cubic/lanczos taps reach past the border
    np.testing.assert_allclose(views[inner], ref[inner], atol=1e-5)


def test_rotated_grid_reads_the_rotated_positions():
    # a smooth analytic sensor image: linear interpolation of a plane is exact
    h, w = 120, 160
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    sensor = (0.3 + 0.002 * xx + 0.001 * yy).astype(np.float32)
    grid = LensGrid("rectangular", 11.3, 2.5, (12.2, 13.7), 8, 11)
    # every view, also those whose samples read across the lens cell (not delivered by default: crosstalk)
    views = decode(sensor, np.ones_like(sensor), grid, 9, centroid_tolerance=None)
    # independent positions: centre + R(θ) @ ((kx-c) s, (ky-c) s)
    t = math.radians(2.5)
    s = 11.3 / 9
    for (ky, kx, r, q) in [(0, 0, 0, 0), (4, 4, 3, 5), (8, 2, 7, 10), (1, 7, 2, 9)]:
        cx = 12.2 + 11.3 * (q * math.cos(t) - r * math.sin(t))
        cy = 13.7 + 11.3 * (q * math.sin(t) + r * math.cos(t))
        dx, dy = (kx - 4) * s, (ky - 4) * s
        x = cx + dx * math.cos(t) - dy * math.sin(t)
        y = cy + dx * math.sin(t) + dy * math.cos(t)
        assert views[ky, kx, r, q, 0] == pytest.approx(0.3 + 0.002 * x + 0.001 * y, abs=2e-6)


def test_devignetting_divides_by_the_white_image():
    h, w = 90, 100
    yy, xx = np.mgrid[0:h, 0:w]
    white = (0.2 + 0.8 * np.exp(-((xx - 50) ** 2 + (yy - 45) ** 2) / 3000.0)).astype(np.float32)
    scene = (0.5 + 0.25 * np.sin(xx / 7.0)).astype(np.float32)
    grid = LensGrid("rectangular", 9.0, 0.0, (4, 4), 10, 11)
    views = decode(scene * white, white, grid, 9, interpolation="nearest")
    ref = decode(scene, np.ones_like(scene), grid, 9, interpolation="nearest")
    np.testing.assert_allclose(views, ref, rtol=1e-5)


def test_dark_samples_are_zero_not_nan():
    m, rows, cols = 5, 3, 3
    white = np.ones((rows * m, cols * m), np.float32)
    white[::m, :] = 0.0  # the first pixel row of every micro image is dark
    sensor = np.full_like(white, 0.7)
    views = decode(sensor, white, aligned_grid(m, rows, cols), m, interpolation="nearest")
    assert np.all(np.isfinite(views))
    # the dark view row is not delivered, nor (so that slices stay evenly bright) its mirror
    assert np.all(views[0] == 0.0) and np.all(views[-1] == 0.0) and np.allclose(views[1:-1], 0.7)
    # every view delivered: the dark samples alone are 0
    views = decode(sensor, white, aligned_grid(m, rows, cols), m, interpolation="nearest", centroid_tolerance=None)
    assert np.all(views[0] == 0.0) and np.allclose(views[1:], 0.7)


@pytest.mark.parametrize("cfa", ["RGGB", "BGGR", "GRBG", "GBRG"])
@pytest.mark.parametrize("method", ["fast", "careful"])
def test_demosaic_constant_colour(cfa, method):
    rgb = np.array([0.2, 0.5, 0.9], np.float32)
    mosaic = np.empty((16, 16), np.float32)
    index = {"R": 0, "G": 1, "B": 2}
    for dy in range(2):
        for dx in range(2):
            mosaic[dy::2, dx::2] = rgb[index[cfa[2 * dy + dx]]]
    out = demosaic(mosaic, cfa, method)
    np.testing.assert_allclose(out[2:-2, 2:-2], np.broadcast_to(rgb, (12, 12, 3)), atol=2e-4)


def test_hex_to_rect_is_exact_for_linear_fields():
    grid = LensGrid("hexagonal", 10.0, 1.0, (5.0, 6.0), 9, 8)
    centers = grid.centers_xy_px()
    field = lambda xy: 0.1 + 0.01 * xy[..., 0] - 0.02 * xy[..., 1]  # noqa: E731
    views = np.broadcast_to(field(centers)[None, None, :, :, None], (3, 3, 9, 8, 1)).astype(np.float32)
    rect, rgrid = hex_to_rect(views, grid)
    assert rgrid.kind == "rectangular" and rect.shape[2:4] == (rgrid.rows, rgrid.cols)
    assert rgrid.rows == 7 and rgrid.cols == 7  # floor(8 * sqrt(3)/2) + 1 rows, cols - 1 columns
    np.testing.assert_allclose(rect[1, 1, :, :, 0], field(rgrid.centers_xy_px()), atol=1e-5)


def test_hexagonal_decode_reads_hex_centres():
    grid = LensGrid("hexagonal", 9.0, 0.0, (6.0, 6.0), 6, 7)
    h, w = 70, 80
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    sensor = (0.1 + 0.003 * xx + 0.002 * yy).astype(np.float32)
    dec = make_decoder(np.ones_like(sensor), grid, 9, centroid_tolerance=None)  # every view (see above)
    x, y = sample_positions(grid, 9)
    views = dec(sensor)
    expect = 0.1 + 0.003 * x + 0.002 * y
    rect_expect, _ = hex_to_rect(expect[..., None].astype(np.float32), grid)
    np.testing.assert_allclose(views, rect_expect, atol=1e-5)


def test_size_mismatch_and_bad_options():
    grid = aligned_grid(3, 2, 2)
    with pytest.raises(LfprocError, match="white image"):
        decode(np.ones((6, 6), np.float32), np.ones((6, 7), np.float32), grid, 3)
    with pytest.raises(LfprocError, match="interpolation"):
        decode(np.ones((6, 6), np.float32), np.ones((6, 6), np.float32), grid, 3, interpolation="spline")
    with pytest.raises(LfprocError, match="black"):
        decode(np.ones((6, 6), np.float32), np.zeros((6, 6), np.float32), grid, 3)
    with pytest.raises(LfprocError, match="odd"):
        decode(np.ones((6, 6), np.float32), np.ones((6, 6), np.float32), grid, 4)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_captures_are_refused(bad):
    grid = aligned_grid(3, 2, 2)
    sensor = np.ones((6, 6), np.float32)
    sensor[2, 3] = bad
    with pytest.raises(LfprocError, match="NaN or infinite"):
        decode(sensor, np.ones((6, 6), np.float32), grid, 3)


def test_demosaic_keeps_noise_below_black_unbiased():
    rng = np.random.default_rng(4)
    mosaic = rng.normal(0.0, 0.01, (64, 64)).astype(np.float32)
    rgb = demosaic(mosaic, "RGGB", "fast")
    assert abs(float(rgb[4:-4, 4:-4].mean())) < 0.001  # clipping at 0 would bias it to about +0.004
    assert rgb.min() < 0


@pytest.mark.parametrize("kind", ["rectangular", "hexagonal"])
@pytest.mark.parametrize("cfa", ["none", "GRBG"])
def test_banded_decode_equals_one_full_size_pass(kind, cfa, monkeypatch):
    """Bands of lens rows (demosaicing only the strip each reads) give exactly the full-size result."""
    from lfproc.decode import _plan, resample_views, sample_positions, to_channels

    rng = np.random.default_rng(7)
    sensor = rng.random((150, 170)).astype(np.float32)
    white = (0.5 + rng.random((150, 170))).astype(np.float32)
    grid = LensGrid(kind, 9.4, 1.5, (8.0, 9.0), 14 if kind == "rectangular" else 16, 16)
    monkeypatch.setattr(_plan, "BAND_BYTES", 1)          # two lens rows per band
    decoder = make_decoder(white, grid, 7, cfa, centroid_tolerance=None)
    kept = decoder.grid
    # the decoder reads sample rows rounded to MAP_STEP px on the sensor (the same for any band split)
    x, y = sample_positions(kept, 7)
    maps = [(x[ky].reshape(-1, kept.cols).astype(np.float32),
             (np.rint(y[ky] / _plan.MAP_STEP) * _plan.MAP_STEP).reshape(-1, kept.cols).astype(np.float32))
            for ky in range(7)]
    reference = resample_views(to_channels(sensor, cfa, "fast"), kept, 7, maps=maps)
    white_views = resample_views(to_channels(white, cfa, "fast"), kept, 7, maps=maps)
    reference = reference / white_views                      # every white sample is bright here
    reference, _ = hex_to_rect(reference.astype(np.float32), kept)
    # float32 division and hexagonal resampling round alike but not always in the same order (Bayer strips
    # are quantised to 16 bits of the whole sensor's range for OpenCV's demosaicing, as the reference is)
    np.testing.assert_allclose(decoder(sensor), reference, rtol=2e-6, atol=1e-6)
