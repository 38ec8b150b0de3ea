"""Issue 14's decode points: partial lenses, views outside the aperture, colour fidelity, any lattice."""

import dataclasses
import math

import numpy as np
import pytest

from lfproc import Camera, LensGrid, geometry, simulate
from lfproc.decode import make_decoder, sample_positions
from lfproc.simulate import Noise, Plane, Scene, Uniform
from lfproc.camera import MainLens


def test_partial_lenses_are_cropped_and_lens_indices_follow_the_grid():
    """The issue's case: 2360 px wide, 27.78 px lenses, 85 columns listed, 83 whole (m̂ = 25)."""
    pitch, m = 250 / 9, 25
    reach = (m - 1) / 2 * pitch / m                     # the outermost sample's offset from its lens centre
    grid = LensGrid("rectangular", pitch, 0.0, (13.0, 20.0), 1, 85)
    height, width = 41, 2360
    # independent count: lens q is whole when 13 + q·pitch ± reach lies on pixel centres 0 … W − 1
    whole = [q for q in range(85) if 13 + q * pitch - reach >= 0 and 13 + q * pitch + reach <= width - 1]
    assert len(whole) == 83 and whole[0] == 1
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float64)
    ramp = (0.2 + 1e-4 * xx + 1e-3 * yy).astype(np.float32)
    decoder = make_decoder(np.ones_like(ramp), grid, m, centroid_tolerance=None)   # every view delivered
    views = decoder(ramp)
    out = decoder.output_grid
    assert (out.rows, out.cols) == (1, 83) and views.shape[2:4] == (1, 83)
    np.testing.assert_allclose(out.lens_xy(0, 0), grid.lens_xy(0, whole[0]))
    # lens j of the views is lens j of the light field's grid, and every sample of every view is the
    # ramp at its nominal position: nothing black, nothing extrapolated from past the border
    x, y = sample_positions(out, m)
    np.testing.assert_allclose(views[..., 0], 0.2 + 1e-4 * x + 1e-3 * y, rtol=1e-5)
    everything = make_decoder(np.ones_like(ramp), grid, m, centroid_tolerance=None, whole_lenses=False)
    x, y = sample_positions(grid, m)
    assert not np.allclose(everything(ramp)[:, :, :, 0, 0], 0.2 + 1e-4 * x[:, :, :, 0] + 1e-3 * y[:, :, :, 0],
                           rtol=1e-5)         # without the crop, lens 0 extrapolates past the border


def test_a_hexagonal_crop_keeps_the_row_parity():
    grid = LensGrid("hexagonal", 9.0, 0.0, (4.5, -2.0), 9, 8)  # row 0 sits above the sensor: partial
    white = np.ones((70, 80), np.float32)
    decoder = make_decoder(white, grid, 7, centroid_tolerance=None)
    kept = decoder.grid
    first_row = round((kept.origin_xy_px[1] - grid.origin_xy_px[1]) / grid.row_spacing_px)
    assert first_row % 2 == 0 and first_row >= 2   # row 1 is whole by y, but would flip the lattice's shift
    np.testing.assert_allclose(kept.centers_xy_px(), grid.centers_xy_px()[first_row:first_row + kept.rows,
                                                                           :kept.cols], atol=1e-9)


def matched_camera(cfa="RGGB"):
    """12 px lenses under an f-number-matched main lens: micro images fill their cells (as on real cameras)."""
    return Camera(0.005, 0.06, 0.24, MainLens(50.0, 50.0, f_number=4.0), grid="rectangular", cfa=cfa, black_level=0, white_level=65535)


def normalised(sim, exposure=0.8):
    scale = np.float32(1.0 / (65535 * exposure))
    return sim.raw.astype(np.float32) * scale, sim.white.astype(np.float32) * scale


@pytest.fixture(scope="module")
def grey_card():
    """A noisy grey card (shot noise of 4000 photons at full scale, 20 DN read noise), Bayer."""
    cam = matched_camera()
    d = geometry.slice_distance_mm(cam, 1.0)
    sim = simulate.render(cam, Scene((Plane(d, Uniform(0.5)),), background=0.1), (360, 480), rotation_deg=-0.4,
                          rim_radius_mm=None, pixel_samples=2, aperture_samples=2, seed=2, shot_noise_photons=4000,
                          read_noise_dn=20, ideal_views=False)
    return cam, sim


def test_views_outside_the_aperture_are_zero(grey_card):
    cam, sim = grey_card
    raw, white = normalised(sim)
    decoder = make_decoder(white, sim.grid, cam.m_hat, "RGGB")
    views = decoder(raw)
    outside = ~geometry.views_inside_aperture(cam)
    assert outside.any() and np.all(views[outside] == 0.0)                  # the documented 0, every channel
    assert np.all(views[~decoder.views_delivered] == 0.0)
    assert np.all(views[decoder.views_delivered][:, 1:-1, 1:-1].mean(axis=(1, 2)) > 0.45)


@pytest.mark.parametrize("method", ["fast", "careful"])
def test_a_grey_card_decodes_grey_within_the_noise(grey_card, method):
    """No green/magenta pattern: every delivered sample within the noise of one raw pixel ratio.

    Demosaicing and interpolation average pixels, so a decoded sample cannot be noisier than the ratio of
    one capture pixel to one white pixel at full white. Its relative σ is sqrt(1/(P·e·g) + 1/(P·e)) plus
    read noise (P photons at full scale, e = 0.8 exposure, g = 0.5 grey). Dim samples (edges of the micro
    images, where the old decoder divided by a small white) amplify it: that is what this catches.
    """
    cam, sim = grey_card
    raw, white = normalised(sim)
    decoder = make_decoder(white, sim.grid, cam.m_hat, "RGGB", demosaic_method=method)
    views = decoder(raw)[:, :, 1:-1, 1:-1]
    photons, read_rel = 4000 * 0.8, 20 / (65535 * 0.8)
    sigma = 0.5 * math.sqrt(1 / (photons * 0.5) + 1 / photons + (read_rel / 0.5) ** 2 + read_rel ** 2)
    delivered = views[decoder.views_delivered]
    # the outer views (won back, issue 20) stand for the partly lit pixels at the micro image's rim: a
    # sample whose white is a fraction f of the bright level has the noise of a pixel at f, σ/√f
    inverse = np.broadcast_to(decoder.inverse_white, decoder.inverse_white.shape[:4] + (3,))  # one channel: all
    white_views = 1.0 / inverse[:, :, 1:-1, 1:-1][decoder.views_delivered]
    bright = np.percentile(white_views, 99, axis=(0, 1, 2))
    for ch in range(3):
        values = delivered[..., ch]
        assert values.std() <= sigma                       # measured 0.010 against sigma = 0.016
        allowed = 6 * sigma * np.sqrt(np.maximum(1.0, bright[ch] / white_views[..., ch]))
        assert np.all(np.abs(values - 0.5) <= allowed)     # a Gaussian tail over ~1e5 samples: < 4.5 sigma
    spans = [np.percentile(delivered[..., ch], 99) - np.percentile(delivered[..., ch], 1) for ch in range(3)]
    assert spans[1] <= 1.25 * min(spans[0], spans[2])     # G no wider than R and B (the issue: 0.48 vs 0.30)


def test_colour_against_the_ideal_views():
    """Per channel, decoded views of a tinted texture against the simulator's ideal views.

    Bilinear demosaicing reads R and B over ±2 px, so they were blurrier than G: 6.9 % of the channel mean
    for R and B and 4.3 % for G (the decoder before it, which delivered the views reading past their micro
    image: 9.4 % and 6.0 %). Rim-aware decoding (the default for Bayer mosaics) takes every channel's
    detail from the pixel itself and the hue from its micro image: 4.3 %, 4.2 %, 4.3 %. 5.5 % leaves room
    for noise, not for a wrong colour balance or bilinear's blur; the means must agree within 1 %.
    """
    cam = matched_camera()
    d = geometry.slice_distance_mm(cam, 1.0)
    feature = 4 * cam.mla_pitch_mm * (d - cam.main_optics.sensor_path_mm(cam.mla_path_mm)) / cam.main_optics.focal_length_mm
    scene = Scene((Plane(d, Noise(feature_mm=feature, seed=3), tint=(0.9, 0.7, 0.5)),), background=0.1)
    sim = simulate.render(cam, scene, (360, 480), rotation_deg=-0.4, rim_radius_mm=None, pixel_samples=3,
                          aperture_samples=3, seed=2)
    raw, white = normalised(sim)
    decoder = make_decoder(white, sim.grid, cam.m_hat, "RGGB")
    views = decoder(raw)
    mask = (sim.ideal_weight > 0.999) & decoder.views_delivered[:, :, None, None]
    mask[:, :, [0, -1], :] = False
    mask[:, :, :, [0, -1]] = False
    for ch, limit in zip(range(3), (0.055, 0.055, 0.055)):
        got, want = views[..., ch][mask], sim.ideal_views[..., ch][mask]
        assert np.mean(got) == pytest.approx(np.mean(want), rel=0.01)
        assert np.sqrt(np.mean((got - want) ** 2)) <= limit * np.mean(want)


@dataclasses.dataclass(frozen=True)
class WavyGrid(LensGrid):
    """A non-rigid lattice: every centre displaced by a smooth function of its rigid position."""

    def lens_xy(self, row, col):
        rigid = LensGrid.lens_xy(self, row, col)
        return rigid + 0.8 * np.stack([np.sin(rigid[..., 1] / 40.0), np.cos(rigid[..., 0] / 50.0)], axis=-1)


def test_samples_follow_any_lattice_the_grid_describes():
    grid = WavyGrid("rectangular", 10.3, 1.0, (9.0, 9.0), 8, 10)
    h, w = 100, 120
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    sensor = (0.1 + 0.003 * xx + 0.002 * yy).astype(np.float32)
    decoder = make_decoder(np.ones_like(sensor), grid, 9, centroid_tolerance=None)
    views = decoder(sensor)
    centres = decoder.output_grid.centers_xy_px()            # the wavy centres of the kept lenses
    u, v = grid.axes
    step = 10.3 / 9
    for ky, kx in [(4, 4), (0, 8), (6, 1)]:
        off = (kx - 4) * step * u + (ky - 4) * step * v
        expect = 0.1 + 0.003 * (centres[..., 0] + off[0]) + 0.002 * (centres[..., 1] + off[1])
        np.testing.assert_allclose(views[ky, kx, :, :, 0], expect, atol=2e-6)
    kept = decoder.output_grid
    rigid = LensGrid.lens_xy(kept, *np.meshgrid(range(kept.rows), range(kept.cols), indexing="ij"))
    assert np.abs(centres - rigid).max() > 0.5        # the samples did follow the deviation


def test_views_of_a_drifting_lattice_follow_the_local_pitch():
    """A lattice whose pitch grows by 4 % across the sensor (a degree-2 deviation in x): the view samples of
    each lens sit at its centre plus (k − c) local steps, the local step being the distance between the
    lens's neighbours / 2 / m̂ (checked with a plain finite difference of the true centre function)."""
    from lfproc.decode import sample_positions
    from lfproc.grid import LensGrid, SmoothDeviation

    m_hat, rows, cols = 7, 12, 40
    # D_x(x̂) = 0.5·γ·hx·(x̂² − 1/3) → dD_x/dx = γ·x̂: the pitch changes by ±γ from the centre to the sides
    hx, gamma = 200.0, 0.02
    coeffs_x = np.zeros((3, 3))
    coeffs_x[2, 0] = gamma * hx / 3.0          # P2(x̂) = (3x̂² − 1)/2
    deviation = SmoothDeviation(2, (200.0, 60.0), (hx, 60.0), tuple(coeffs_x.ravel()), tuple(np.zeros(9)))
    grid = LensGrid("rectangular", 10.0, 0.0, (5.0, 5.0), rows, cols, deviation=deviation)
    x, y = sample_positions(grid, m_hat)
    c = (m_hat - 1) // 2
    for r, q in [(3, 1), (6, 20), (9, 38)]:
        left, right = grid.lens_xy(r, q - 1), grid.lens_xy(r, q + 1)
        local_step = (right - left)[0] / 2 / m_hat
        centre = grid.lens_xy(r, q)
        for k in (0, c, m_hat - 1):
            assert x[c, k, r, q] == pytest.approx(centre[0] + (k - c) * local_step, abs=0.02)
            assert y[k, c, r, q] == pytest.approx(centre[1] + (k - c) * local_step, abs=0.02)
    # the pitch really drifts: the local steps at the two sides differ by about 2·γ
    steps = [(grid.lens_xy(5, q + 1) - grid.lens_xy(5, q - 1))[0] / 2 for q in (1, 38)]
    assert steps[1] / steps[0] > 1.03
