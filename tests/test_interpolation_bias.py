"""Interpolation bias (issue 21, point 3): the sharpest slice of a fine sweep sits at the true a.

With linear interpolation an interpolated slice is blurrier than a whole-lens one (a pure gather), so a
slice's sharpness has a cusp at integer a and "sharpest slice" snaps to it (to a = 0 in a microscope,
whose useful a lie below about 0.25). The commands' default, ``"cubic-sharp"``, must hold the true a
within 0.01 for photographic captures (m̂ = 9) and 0.005 for microscope ones (m̂ = 15, small a).

The light fields are exact renders of a textured plane: a random texture with natural-image statistics
(power ∝ 1/f²) seen by view k shifted by a0·(c − k) lenses, each sample the texture integrated over its
lens (so what lies beyond the lens grid's Nyquist frequency aliases, as in a capture). The sharpness
measure (the slice's variance inside the border that every view reaches) is checked to be unbiased
itself: with exact (Fourier) shifts of a band-limited texture its peak is the true a.
"""

import numpy as np
import pytest

import lfproc
from lfproc.cli import build_parser
from lfproc.simulate import plane_views

SWEEP_HALF, SWEEP_STEP = 0.03, 0.001


def sharpness(stack, a_values, m):
    """Variance of each slice inside the border band that some view's shift leaves (K,)."""
    border = int(np.ceil(np.abs(a_values).max() * (m - 1) / 2)) + 3
    inner = stack[:, border:-border, border:-border, 0]
    return inner.reshape(len(inner), -1).var(axis=1)


def sweep(a0):
    return np.round(np.arange(a0 - SWEEP_HALF, a0 + SWEEP_HALF + SWEEP_STEP / 2, SWEEP_STEP), 9)


def sharpest(views, a0, interpolation):
    a = sweep(a0)
    stack = lfproc.refocus(views, a, interpolation=interpolation)
    return float(a[int(np.argmax(sharpness(stack, a, views.shape[0])))])


def fourier_refocus(views, a):
    """Eq. 9 with exact (periodic Fourier) shifts: the reference that has no interpolation at all."""
    m, _, ny, nx = views.shape[:4]
    c = (m - 1) // 2
    fy, fx = np.fft.fftfreq(ny)[:, None], np.fft.fftfreq(nx)[None, :]
    spectra = np.fft.fft2(views[..., 0].astype(np.float64))
    k = c - np.arange(m)
    out = []
    for value in a:
        phase_y = np.exp(2j * np.pi * value * k[:, None, None] * fy)       # (m, ny, 1)
        phase_x = np.exp(2j * np.pi * value * k[:, None, None] * fx)       # (m, 1, nx)
        total = np.einsum("yab,yxab,xab->ab", phase_y * np.ones((1, 1, nx)), spectra,
                          phase_x * np.ones((1, ny, 1)))
        out.append(np.fft.ifft2(total / m**2).real)
    return np.array(out)[..., None]


PHOTOGRAPHIC = [0.1, 0.25, 0.5, 0.75, 0.9, 1.1, 1.25, 1.5, 1.75, 1.9]
MICROSCOPE = [-0.05, 0.01, 0.025, 0.05, 0.1, 0.2]


def test_sharpness_measure_is_unbiased():
    """Exact shifts of a band-limited plane (no aliasing, no interpolation): the measure peaks at a0."""
    for a0 in (0.1, 0.5, 0.9):
        views = plane_views(9, 32, a0, seed=3, oversample=1, band=0.45)
        a = sweep(a0)
        found = a[int(np.argmax(sharpness(fourier_refocus(views, a), a, 9)))]
        assert abs(found - a0) < 0.75 * SWEEP_STEP, (a0, found)


def test_linear_interpolation_snaps_to_integer_a():
    """The bias this issue is about, and the reason the commands no longer default to linear."""
    errors = [sharpest(plane_views(9, 48, a0, seed=1), a0, "linear") - a0 for a0 in (0.1, 0.9)]
    assert max(abs(e) for e in errors) > 0.02, errors
    assert errors[0] < 0 < errors[1]      # towards a = 0 and a = 1


def test_photographic_sharpest_slice_within_0_01():
    errors = [sharpest(plane_views(9, 64, a0, seed=1), a0, "cubic-sharp") - a0 for a0 in PHOTOGRAPHIC]
    assert max(abs(e) for e in errors) <= 0.01 + 1e-9, dict(zip(PHOTOGRAPHIC, np.round(errors, 4)))


def test_microscope_sharpest_slice_within_0_005():
    errors = [sharpest(plane_views(15, 64, a0, seed=2), a0, "cubic-sharp") - a0 for a0 in MICROSCOPE]
    assert max(abs(e) for e in errors) <= 0.005 + 1e-9, dict(zip(MICROSCOPE, np.round(errors, 4)))


@pytest.mark.parametrize("command", ["refocus", "batch"])
def test_commands_default_to_cubic_sharp(command):
    parser = build_parser()
    args = parser.parse_args([command, "x.raw", "--camera", "c.toml", "--white", "w.tif", "--a", "0", "-o", "out"])
    assert args.interpolation == "cubic-sharp"


def test_cubic_sharp_is_an_interpolation():
    """Keys' kernel with a = −0.9 reproduces the lenses at whole positions and a linear ramp between them."""
    ramp = np.broadcast_to(np.arange(20, dtype=np.float32)[None, :, None], (20, 20, 1))
    views = np.broadcast_to(ramp, (3, 3, 20, 20, 1)).copy()
    out = lfproc.refocus(views, 0.3, interpolation="cubic-sharp")
    inner = out[3:-3, 3:-3, 0]
    assert np.allclose(inner, np.arange(20, dtype=np.float32)[3:-3][None, :], atol=1e-5)
    whole = lfproc.refocus(views, 1.0, interpolation="cubic-sharp")
    assert np.array_equal(whole, lfproc.refocus(views, 1.0, interpolation="nearest"))
