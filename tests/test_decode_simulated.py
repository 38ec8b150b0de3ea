"""Decoding simulated captures against the simulator's ideal views (issue: 9 um pixels under 250 um lenses)."""

import dataclasses

import numpy as np
import pytest

from lfproc import Camera, geometry
from lfproc import simulate
from lfproc.decode import decode, make_decoder
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

from conftest import SAMPLES


def psnr_db(views, ideal, weight, rings_excluded=1):
    """PSNR over samples every ray of which passes, lenses off the border, views inside the outer ring(s).

    The outermost ring of views is excluded: its effective pixel reaches the micro image's edge, so any
    interpolation reads the neighbouring micro image too (crosstalk, documented in lfproc.decode).
    """
    m = views.shape[0]
    c = (m - 1) // 2
    ky, kx = np.mgrid[0:m, 0:m]
    ring = np.maximum(abs(ky - c), abs(kx - c))
    mask = (weight > 0.999) & (ring <= c - rings_excluded)[:, :, None, None]
    mask[:, :, [0, -1], :] = False
    mask[:, :, :, [0, -1]] = False
    err = (views - ideal)[mask]
    return 10 * np.log10(ideal[mask].max() ** 2 / np.mean(err ** 2))


def normalised(sim):
    cam = sim.camera
    black, white = cam.raw_levels(65535.0)
    scale = 1.0 / (white - black)
    return ((sim.raw.astype(np.float32) - cam.black_level) * scale,
            (sim.white.astype(np.float32) - cam.black_level) * scale)


@pytest.fixture(scope="module")
def paper_9um():
    """The paper's f100 camera with 9 um pixels: 27.78 px per lens, resampled to m = 25 (Section 5.1)."""
    cam = dataclasses.replace(Camera.from_toml(SAMPLES / "cameras" / "paper-f100.toml"), pixel_pitch_mm=0.009)
    assert cam.m_hat == 25 and cam.pitch_px == pytest.approx(250 / 9)
    d = geometry.slice_distance_mm(cam, 1.0)
    feature = 4 * cam.mla_pitch_mm * (d - cam.main_optics.sensor_path_mm(cam.mla_path_mm)) / cam.main_optics.focal_length_mm
    scene = Scene((Plane(d, Noise(feature_mm=feature, seed=1)),), background=0.1)
    # fine quadrature: the ideal views and the sensor integrate the same rays at different positions
    sim = simulate.render(cam, scene, (336, 448), rotation_deg=0.4, offset_px=(0.3, -0.2), rim_radius_mm=None,
                          pixel_samples=4, aperture_samples=5, seed=1)
    return sim


def test_9um_capture_decodes_into_25x25_views_matching_the_sensor(paper_9um):
    raw, white = normalised(paper_9um)
    views = decode(raw, white, paper_9um.grid, 25, interpolation="linear")
    grid = paper_9um.grid
    assert views.shape == (25, 25, grid.rows, grid.cols, 1)
    # the lens count matches the sensor: as many lenses as whole pitches fit (less the half-pitch margin)
    assert grid.cols == pytest.approx(448 / (250 / 9), abs=2) and grid.rows == pytest.approx(336 / (250 / 9), abs=2)
    assert np.all(np.isfinite(views))


@pytest.mark.parametrize("interpolation, floor_db", [("nearest", 30.0), ("linear", 35.0), ("cubic", 35.0),
                                                     ("lanczos", 35.0)])
def test_decoded_views_match_ideal_views(paper_9um, interpolation, floor_db):
    raw, white = normalised(paper_9um)
    decoder = make_decoder(white, paper_9um.grid, 25, interpolation=interpolation)
    views = decoder(raw)
    # every view whose kernel (interpolation reach, 1 px linear .. 4 px Lanczos) stays inside its own micro
    # image is delivered; a wider kernel cut at the micro image's edge moves the ray a sample stands for,
    # and those views are not delivered (lfproc.decode._view_mask)
    reach = {"nearest": 1, "linear": 1, "cubic": 2, "lanczos": 4}[interpolation] / (paper_9um.grid.pitch_px / 25)
    m, c = 25, 12
    ky, kx = np.mgrid[0:m, 0:m]
    inside = np.maximum(abs(ky - c), abs(kx - c)) <= c - 1 - int(np.ceil(reach))
    assert decoder.views_delivered[inside].all()
    weight = paper_9um.ideal_weight * decoder.views_delivered[:, :, None, None]
    assert psnr_db(views, paper_9um.ideal_views, weight) >= floor_db


def test_registration_is_exact(paper_9um):
    """Any half-pixel error in the sample positions costs far more than the interpolation does."""
    raw, white = normalised(paper_9um)
    best = psnr_db(decode(raw, white, paper_9um.grid, 25), paper_9um.ideal_views, paper_9um.ideal_weight)
    for dx, dy in [(0.5, 0.0), (0.0, -0.5)]:
        moved = dataclasses.replace(paper_9um.grid, origin_xy_px=(paper_9um.grid.origin_xy_px[0] + dx,
                                                                   paper_9um.grid.origin_xy_px[1] + dy))
        assert psnr_db(decode(raw, white, moved, 25), paper_9um.ideal_views, paper_9um.ideal_weight) < best - 6


@pytest.mark.parametrize("kind", ["rectangular", "hexagonal"])
def test_bayer_and_hexagonal_captures(kind):
    cam = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), grid=kind, cfa="RGGB", black_level=64, white_level=16383)
    d = geometry.slice_distance_mm(cam, 0.5)
    scene = Scene((Plane(d, Noise(feature_mm=12.0, seed=2), tint=(1.0, 0.7, 0.4)),), background=0.1)
    sim = simulate.render(cam, scene, (240, 300), rotation_deg=-0.6, rim_radius_mm=None, pixel_samples=3,
                          aperture_samples=4, seed=3)
    raw, white = normalised(sim)
    decoder = make_decoder(white, sim.grid, cam.m_hat, "RGGB", interpolation="linear")
    views = decoder(raw)
    # views whose samples read past their own lit micro image are not delivered (0: their parallax is
    # biased, issue 13); every view within two rings of the centre is
    ky, kx = np.mgrid[0:cam.m_hat, 0:cam.m_hat]
    ring = np.maximum(abs(ky - cam.center_index), abs(kx - cam.center_index))
    assert decoder.views_delivered[ring <= 2].all()
    if kind == "hexagonal":
        from lfproc.decode import hex_to_rect
        ideal, _ = hex_to_rect(sim.ideal_views, sim.grid)
        weight, _ = hex_to_rect(sim.ideal_weight[..., None], sim.grid)
        weight = weight[..., 0]
    else:
        ideal, weight = sim.ideal_views, sim.ideal_weight
    assert views.shape == ideal.shape and views.shape[-1] == 3
    # colour is right: per-channel means agree within 2 % (white balance comes from the white image)
    mask = (weight > 0.999) & decoder.views_delivered[:, :, None, None]
    for ch in range(3):
        assert views[..., ch][mask].mean() == pytest.approx(ideal[..., ch][mask].mean(), rel=0.02)
    # bilinear demosaicing of 11 px micro images reads the neighbour micro image in the two outer
    # rings; inside them it measured 43 dB (both grids), so 38 dB leaves room for noise, not for bugs
    assert psnr_db(views, ideal, weight * decoder.views_delivered[:, :, None, None], rings_excluded=2) >= 38.0
