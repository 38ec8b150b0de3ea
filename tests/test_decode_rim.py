"""Rim-aware Bayer decoding (issue 20): every channel of a sample at its own pixel's ray, cell borders that
pass a pixel from one lens to the next smoothly, and views that a calibration's grid error barely moves.

References are independent of the decoder: the kernel's formula written out by hand on a tiny mosaic,
the simulator's ideal views of a tinted plane, and the same capture decoded with a grid moved by about
a calibration's error.
"""

import dataclasses

import numpy as np
import pytest

from lfproc import Camera, geometry, simulate
from lfproc.decode import make_decoder
from lfproc.decode._cells import CLASSES, SHARE_WIDTH_PX, cell_classes, cell_shares, class_weight
from lfproc.decode._rim_demosaic import RATIO_FLOOR, RATIO_LIMIT, balanced_white, phase_channels
from lfproc.decode._rim_kernel import rim_stack
from lfproc.grid import LensGrid
from lfproc.simulate import Noise, Plane, Scene, Uniform
from lfproc.camera import MainLens


class _Generic(LensGrid):
    """A LensGrid subclass: cell_shares takes its generic (numpy) path, not the compiled rigid one."""


@pytest.mark.parametrize("kind", ["rectangular", "hexagonal"])
def test_cell_shares_sum_to_one_and_follow_the_grid_continuously(kind):
    grid = LensGrid(kind, 11.3, 0.4, (9.6, 10.2), 12, 12)
    shape = (120, 130)
    classes = cell_classes(grid, shape)
    second, share = cell_shares(grid, shape, classes=classes)
    total = sum(class_weight(classes, second, share, c) for c in range(CLASSES))
    np.testing.assert_allclose(total, 1.0, atol=1e-6)
    # pixels on a cell border are shared; deep inside a cell they are the lens's alone
    assert 0.05 < np.mean(share < 255) < 0.4
    # the compiled kernel for rigid lattices gives what the generic code gives
    generic = cell_shares(_Generic(kind, 11.3, 0.4, (9.6, 10.2), 12, 12), shape, classes=classes)
    assert np.array_equal(generic[0], second) and np.array_equal(generic[1], share)
    # a grid moved by 0.01 px moves a pixel's weight in a class by about 0.01 / width, not by a whole pixel
    # (a hard border hands a pixel from one lens to the other). Only where two borders meet (the corners
    # between micro images, dark on a real sensor) can the rest of a shared pixel pass to the third lens.
    moved = dataclasses.replace(grid, origin_xy_px=(9.61, 10.19))
    classes_m = cell_classes(moved, shape)
    second_m, share_m = cell_shares(moved, shape, classes=classes_m)
    bound = 0.0142 / SHARE_WIDTH_PX + 1.0 / 255 + 1e-6
    jumps = np.zeros(shape, bool)
    for c in range(CLASSES):
        change = np.abs(class_weight(classes_m, second_m, share_m, c) - class_weight(classes, second, share, c))
        jumps |= change > bound
    assert jumps.mean() < 0.005
    hard = dataclasses.replace(grid, origin_xy_px=(9.61, 10.19))
    assert np.mean(cell_classes(hard, shape) != classes) > 5 * jumps.mean()   # what a hard border flips


def test_each_pixel_keeps_its_own_value_and_takes_the_lens_hue_for_the_other_channels():
    """The kernel against its formula, written out here on a 2 x 2-lens RGGB mosaic."""
    grid = LensGrid("rectangular", 8.0, 0.0, (3.5, 3.5), 2, 2)
    shape = (16, 16)
    rng = np.random.default_rng(3)
    white = rng.uniform(0.5, 1.0, shape).astype(np.float32)
    raw = (white * rng.uniform(0.1, 0.9, shape)).astype(np.float32)
    wb, levels = balanced_white(white, 0.05)
    classes = cell_classes(grid, shape)
    second, share = cell_shares(grid, shape, classes=classes)
    chan = phase_channels("RGGB")
    u, v = grid.axes
    lattice = np.array([3.5, 3.5, u[0], u[1], v[0], v[1], 8.0, 8.0, 0.0])
    gap = 2
    stack = np.full((CLASSES * (shape[0] + 2 * gap), shape[1], 3), np.nan, np.float32)
    rim_stack(raw, wb, classes, second, share, 1.0 / levels, chan.astype(np.int64), 0, lattice, gap,
              RATIO_FLOOR, RATIO_LIMIT, stack)
    assert np.all(np.isfinite(stack))
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]]
    phase = 2 * (yy % 2) + xx % 2
    value = raw / levels[phase]            # the capture in the balanced white's units
    lens = (yy // 8) * 2 + xx // 8          # the lens of each pixel (cells are the 8 x 8 squares)
    for cls in range(CLASSES):
        weight = class_weight(classes, second, share, cls)
        plane = stack[gap + cls * (shape[0] + 2 * gap):][:shape[0]]
        for r in range(2):
            for q in range(2):
                if 2 * (r % 2) + q % 2 != cls:
                    continue
                pix = (lens == 2 * r + q) & (weight > 0)
                # the hue of lens (r, q): white-weighted channel means over the pixels it owns (by share)
                sums = np.zeros((3, 2))
                for y, x in zip(*np.nonzero(weight > 0)):
                    if abs(y + 0.5 - (8 * r + 4)) < 8 and abs(x + 0.5 - (8 * q + 4)) < 8:
                        sums[chan[phase[y, x]]] += weight[y, x] * np.array([value[y, x], wb[y, x]])
                means = sums[:, 0] / sums[:, 1]
                for y, x in zip(*np.nonzero(pix)):
                    a = chan[phase[y, x]]
                    rho = value[y, x] / wb[y, x]
                    want = np.empty(3)
                    for ch in range(3):
                        gain = np.clip((means[ch] + RATIO_FLOOR) / (means[a] + RATIO_FLOOR), 1 / RATIO_LIMIT,
                                       RATIO_LIMIT)
                        want[ch] = rho if ch == a else max(means[ch] + gain * (rho - means[a]), 0.0)
                    np.testing.assert_allclose(plane[y, x], weight[y, x] * wb[y, x] * want, rtol=2e-5, atol=1e-7)


def _tinted_render(tint, seed=2):
    cam = Camera(0.005, 0.06, 0.24, MainLens(50.0, 50.0, f_number=4.0), grid="rectangular", cfa="RGGB", black_level=0, white_level=65535)
    d = geometry.slice_distance_mm(cam, 1.0)
    scene = Scene((Plane(d, Uniform(0.8), tint=tint),), background=0.1)
    sim = simulate.render(cam, scene, (240, 300), rotation_deg=-0.4, rim_radius_mm=None, pixel_samples=2,
                          aperture_samples=2, seed=seed, shot_noise_photons=4000, read_noise_dn=20)
    scale = np.float32(1.0 / 65535)
    return cam, sim, sim.raw.astype(np.float32) * scale, sim.white.astype(np.float32) * scale


def test_a_saturated_colour_keeps_the_noise_of_its_dark_channels_out_of_the_bright_one():
    """A pure red card (tint 0.9, 0.002, 0.002): green and blue pixels see almost nothing but their noise.
    Their red comes from the lens's hue ratio (about 400) times their own detail; unclipped, that ratio
    multiplies their noise into red (measured: 18 % noise on a uniform card). Clipped to 4: 1.1 %."""
    cam, sim, raw, white = _tinted_render((0.9, 0.002, 0.002))
    decoder = make_decoder(white, sim.grid, cam.m_hat, "RGGB")
    views = decoder(raw)[decoder.views_delivered][:, 1:-1, 1:-1]
    ideal = sim.ideal_views[decoder.views_delivered][:, 1:-1, 1:-1]
    assert np.all(np.isfinite(views))
    red, dark = float(ideal[..., 0].mean()), float(ideal[..., 1].mean())
    assert views[..., 0].mean() == pytest.approx(red, rel=0.01)
    assert views[..., 0].std() < 0.03 * red
    for ch in (1, 2):
        assert views[..., ch].mean() == pytest.approx(dark, abs=0.005 * red)
        assert np.percentile(views[..., ch], 99.9) < 0.05 * red


def test_a_calibrations_grid_error_moves_the_delivered_views_little():
    """The demo sample decoded with its grid and with the grid moved by (0.03, −0.02) px (about a
    calibration's residual): the outer views, read at the rim of the micro images, change a little more
    than the inner ones but by far less than the 0.06–0.11 RMS of a decoder that handed rim pixels from one
    lens to the next at a hard border (docs/decoding.md). Measured: 43 dB, worst view 0.023 RMS."""
    from conftest import SAMPLES
    from lfproc.io import read_capture
    from lfproc.api import prepare_decoding

    camera = Camera.from_toml(str(SAMPLES / "sample" / "camera.toml"))
    setup = prepare_decoding(camera, white=str(SAMPLES / "sample" / "white.png"), cache=True)
    white = read_capture(str(SAMPLES / "sample" / "white.png"), camera)
    capture = read_capture(str(SAMPLES / "sample" / "capture.png"), camera)
    grid = setup.grid
    moved = dataclasses.replace(grid, origin_xy_px=(grid.origin_xy_px[0] + 0.03, grid.origin_xy_px[1] - 0.02))
    first = make_decoder(white.data, grid, camera.m_hat, white.cfa)
    second = make_decoder(white.data, moved, camera.m_hat, white.cfa)
    assert first.views_delivered.sum() >= 0.9 * geometry.views_inside_aperture(camera).sum()
    assert np.array_equal(first.views_delivered, second.views_delivered)
    a, b = first(capture.data), second(capture.data)
    rows, cols = min(a.shape[2], b.shape[2]), min(a.shape[3], b.shape[3])
    a, b = a[:, :, :rows, :cols], b[:, :, :rows, :cols]
    kept = first.views_delivered
    psnr = 10 * np.log10(a[kept].max() ** 2 / np.mean((a[kept] - b[kept]) ** 2))
    per_view = np.sqrt(np.mean((a - b) ** 2, axis=(2, 3, 4)))[kept]
    assert psnr > 40.0
    assert per_view.max() < 0.035 and np.median(per_view) < 0.01
