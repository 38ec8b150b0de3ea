"""The wave-optics forward model of lfproc.wave (issue 39): against pyolaf, against ray optics, and its bookkeeping.

* pyolaf 0.2.1 (an independent program, the Python port of oLaF): its light-field PSFs of the real sea-urchin
  optics at three depths, stored small in tests/data/pyolaf_psf.npz by ``scripts/compare_pyolaf.py
  --write-test-reference``; lfproc at pyolaf's sampling (one field sample per pixel) reproduces them;
* the field sampling converges (the pixel-integrated default against 7 × 7 sub-samples);
* geometric optics: a defocused point's light reaches the lenses its ray cone covers, and in each micro image
  it lands where the chief ray through that lens centre goes — on the side of the point for z > 0 (image
  behind the lenslets), on the other side for z < 0;
* the classes built by mirror symmetry equal the classes computed one by one; the projector equals a direct
  convolution, and its back projection is the exact adjoint.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

import lfproc
from lfproc.camera import Microscope
from lfproc.errors import LfprocError
from lfproc.wave import (Projector, backend, blur_radius_lenses, build_operators, image_defocus_um, lens_radius,
                         voxel_patterns)

DATA = os.path.join(os.path.dirname(__file__), "data", "pyolaf_psf.npz")


def microscope_camera(m_hat=15, pitch_mm=0.125, f_s_mm=2.433, grid="rectangular", wavelength_nm=482.0):
    """The sea-urchin rig's optics (20x/0.5 water, 125 µm lenslets at 2433 µm) with m̂ samples per lens."""
    return lfproc.Camera(pixel_pitch_mm=pitch_mm / m_hat, mla_pitch_mm=pitch_mm, mla_focal_length_mm=f_s_mm, grid=grid,
                         main_optics=Microscope(20.0, 0.5, 1.33, 200.0, wavelength_nm=wavelength_nm), micro_image_px=m_hat)


def _closeness(a, b):
    a, b = np.ravel(a) / np.sum(a), np.ravel(b) / np.sum(b)
    return float(np.corrcoef(a, b)[0, 1]), float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _as_image(pattern):
    """(m̂, m̂, K, K) → the rectified image (K·m̂)²."""
    m, _, k, _ = pattern.shape
    return pattern.transpose(2, 0, 3, 1).reshape(k * m, k * m)


def test_the_psfs_are_pyolafs_at_its_sampling():
    """pyolaf samples the field at one point per pixel; so sampled, lfproc's PSFs are pyolaf's (NCC ≥ 0.999,
    relative L2 ≤ 3 %: measured 0.9997–0.9998 and 2.1–2.4 %, the rest being pyolaf's obliquity factor (1 + cos θ)
    that lfproc's aplanatic emission pupil does not have: with it the difference is 0.6–0.9 %)."""
    ref = np.load(DATA)
    camera = microscope_camera()
    optics = camera.main_optics.wave_optics
    for depth, offset, theirs, half in zip(ref["z_um"], ref["offset_um"], ref["patterns"], ref["half"]):
        r = lens_radius(optics, 125.0, float(depth))
        mine = _as_image(voxel_patterns(optics, 125.0, 2433.0, 15, 1, float(depth), [offset], r)[0])
        # pyolaf's pattern is centred on the voxel (offset / 25 µm · 3 px from the lens centre)
        size, k = theirs.shape[0], mine.shape[0]
        canvas = np.zeros((size + 2 * k, size + 2 * k))
        shift = np.round(np.asarray(offset) / (125.0 / 15)).astype(int)
        y0, x0 = k + int(half) - (k - 1) // 2 - shift[0], k + int(half) - (k - 1) // 2 - shift[1]
        canvas[y0:y0 + k, x0:x0 + k] = mine
        ncc, rel = _closeness(canvas[k:k + size, k:k + size], theirs)
        assert ncc >= 0.999 and rel <= 0.03, (depth, ncc, rel)


def test_pixel_integration_has_converged():
    """lfproc's default (each pixel integrated on q × q sub-samples, q from the field's Nyquist rate) is within
    2.5 % (L2) of 7 × 7 sub-samples; pyolaf's one sample per pixel is 50 % off at this depth."""
    camera = microscope_camera()
    optics = camera.main_optics.wave_optics
    r = lens_radius(optics, 125.0, 40.0)
    patterns = {q: voxel_patterns(optics, 125.0, 2433.0, 15, q, 40.0, [(-25.0, -50.0)], r)[0] for q in (1, 3, 7)}
    assert _closeness(patterns[3], patterns[7])[1] < 0.025
    assert _closeness(patterns[1], patterns[7])[1] > 0.3


@pytest.mark.parametrize("z_um", [-60.0, 60.0])
def test_a_defocused_point_goes_where_its_rays_go(z_um):
    """Ray optics: the image of a point at depth z lies Δ = z·M²/n behind the lenslets; lens c sees it along the
    chief ray through its centre, landing (x_p − c)·f_s/Δ from the lens centre on the sensor, and only the lenses
    inside the cone of half-angle asin(NA/M) around the image point receive light."""
    camera = microscope_camera()
    optics = camera.main_optics.wave_optics
    r = lens_radius(optics, 125.0, z_um)
    point = (0.0, 25.0)                                   # a fifth of a lens right of the lens centre
    pattern = voxel_patterns(optics, 125.0, 2433.0, 15, 3, z_um, [point], r)[0]     # (u, u, k, k)
    delta = float(image_defocus_um(optics, z_um))
    sample = 125.0 / 15
    u = (np.arange(15) - 7) * sample
    radius = float(blur_radius_lenses(optics, 125.0, z_um))
    for kx in range(-r, r + 1):
        lens = pattern[:, :, r, r + kx]
        light = lens.sum()
        centre_x = kx * 125.0
        if abs(centre_x - point[1]) < 0.7 * radius * 125.0:             # well inside the cone: lit, where the ray goes
            landing = float((lens.sum(axis=0) * u).sum() / light)
            expected = (point[1] - centre_x) * 2433.0 / delta
            assert abs(landing - expected) < 0.5 * sample, (kx, landing, expected)
        elif abs(centre_x - point[1]) > radius * 125.0 + 2 * 125.0:     # two lenses beyond the cone: dark
            assert light < 2e-3, (kx, light)


def test_mirror_symmetry_gives_the_classes_computed_one_by_one():
    camera = microscope_camera(m_hat=9)
    optics = camera.main_optics.wave_optics
    ops = build_operators(camera, [-30.0, 20.0], 3)
    offsets = (np.arange(3) - 1) * 125.0 / 3
    for i, depth in enumerate(ops.z_um):
        r = lens_radius(optics, 125.0, float(depth))
        pad = ops.radius - r
        direct = voxel_patterns(optics, 125.0, 2433.0, 9, ops.oversample, float(depth),
                                [(offsets[a], offsets[b]) for a in range(3) for b in range(3)], r)
        kept = direct[:, ops.views[:, 0], ops.views[:, 1]]
        stored = ops.kernels[i][:, :, pad:pad + 2 * r + 1, pad:pad + 2 * r + 1]
        np.testing.assert_allclose(stored, kept, atol=1e-7)
        assert np.all(ops.kernels[i].sum(axis=(1, 2, 3)) > 0.999)       # the views left out hold < 0.1 %


def test_the_projector_is_a_convolution_and_its_adjoint():
    from scipy.signal import convolve2d, correlate2d

    ops = build_operators(microscope_camera(m_hat=5), [-20.0, 30.0], 3)
    rng = np.random.default_rng(1)
    ny, nx = 23, 19
    volume = rng.random((ops.kernels.shape[0] * 9, ny, nx)).astype(np.float32)
    data = rng.random((len(ops.views), ny, nx)).astype(np.float32)
    h = ops.kernels.reshape(-1, *ops.kernels.shape[2:])
    expected_y = np.zeros(data.shape)
    expected_x = np.zeros(volume.shape)
    for p in range(h.shape[0]):
        for u in range(h.shape[1]):
            expected_y[u] += convolve2d(volume[p], h[p, u], mode="same")
            expected_x[p] += correlate2d(data[u], h[p, u], mode="same")
    for memory in (2 ** 30, 2 ** 18):                  # one large tile, or many small ones
        projector = Projector(ops, (ny, nx), memory=memory)
        y, x = projector.forward(volume), projector.backward(data)
        assert np.abs(y - expected_y).max() < 2e-6 * np.abs(expected_y).max()
        assert np.abs(x - expected_x).max() < 2e-6 * np.abs(expected_x).max()
        assert np.vdot(y.astype(np.float64), data) == pytest.approx(np.vdot(volume.astype(np.float64), x), rel=1e-6)


class _Recording:
    """An array module that forwards to NumPy and records what was asked of it."""

    def __init__(self):
        self.asked = set()

    def __getattr__(self, name):
        self.asked.add(name)
        return getattr(np, name)


def test_the_arithmetic_goes_through_the_backend():
    """The one seam: the projector does its arithmetic through ``backend.xp`` (CuPy's place); a module that
    forwards to NumPy gives NumPy's results. CuPy itself is refused in one line where it is not installed."""
    from lfproc.wave import Backend

    ops = build_operators(microscope_camera(m_hat=7), [0.0, 30.0], 3)
    volume = np.random.default_rng(2).random((ops.kernels.shape[0] * 9, 12, 12)).astype(np.float32)
    recording = _Recording()
    seam = Backend("numpy", recording, workers=1)
    mine = Projector(ops, (12, 12), backend=seam).forward(volume)
    np.testing.assert_allclose(mine, Projector(ops, (12, 12)).forward(volume), rtol=1e-6, atol=1e-9)
    assert {"matmul", "zeros", "empty"} <= recording.asked
    try:
        import cupy  # noqa: F401
    except ImportError:
        with pytest.raises(LfprocError, match="cupy"):
            backend("cupy")


def test_refusals_are_one_line():
    camera = microscope_camera(m_hat=9)
    with pytest.raises(LfprocError, match="superres=10 is finer than the 9 samples"):
        build_operators(camera, [0.0], 10)
    with pytest.raises(LfprocError, match=r"these optics image z from -\d.* to \d.* um"):
        build_operators(camera, [0.0, 5000.0], 3)
    photo = lfproc.Camera.from_toml(os.path.join(os.path.dirname(lfproc.__file__), "samples", "cameras",
                                                 "paper-f100.toml"))
    with pytest.raises(LfprocError, match="microscope optics"):
        build_operators(photo, [0.0], 1)
    with pytest.raises(LfprocError, match="rectangular lenslet grids only"):
        build_operators(microscope_camera(m_hat=9, grid="hexagonal"), [0.0], 1)


def test_an_off_centre_view_centre_reads_the_neighbouring_samples():
    """A decoder that reads the views around an off-centre NA disc (``LightField.view_centre``): with the central
    view one sample off the lens centre, view u reads where view u + 1 read before."""
    camera = microscope_camera(m_hat=7)
    optics = camera.main_optics.wave_optics
    r = lens_radius(optics, 125.0, 25.0)
    centred = voxel_patterns(optics, 125.0, 2433.0, 7, 3, 25.0, [(10.0, -20.0)], r)[0]
    moved = voxel_patterns(optics, 125.0, 2433.0, 7, 3, 25.0, [(10.0, -20.0)], r, sample_shift=(0.0, 1.0))[0]
    assert np.abs(moved[:, :-1] - centred[:, 1:]).max() < 1e-3 * centred.max()
    assert np.abs(moved[:, 1:] - centred[:, 1:]).max() > 0.1 * centred.max()     # and it did move
