"""Interpolation bias (issue 21, point 3): the sharpest slice of a fine sweep sits at the true a.

With linear interpolation an interpolated slice is blurrier than a whole-lens one (a pure gather), so a
slice's sharpness has a cusp at integer a and "sharpest slice" snaps to it (to a = 0 in a microscope,
whose useful a lie below about 0.25). The commands' default, ``"cubic-spline"`` (the cubic spline through
each view), must hold the true a within 0.01 for photographic captures (m̂ = 9) and 0.005 for microscope
ones (m̂ = 15, small a), for textures of power ∝ 1/f^1.5, 1/f² (natural images) and 1/f³, whatever the
fractional part of a, and on the photographic simulator's renders of the bundled sample camera.

The light fields are exact renders of a textured plane (:func:`lfproc.simulate.plane_views`): view k sees
the texture shifted by a0·(c − k) lenses, each sample the texture integrated over its lens, so what lies
beyond the lens grid's Nyquist frequency aliases, as in a capture. Sharpness is
:func:`lfproc.refocusing.slice_sharpness`, the power below a quarter cycle per lens: checked to be unbiased
itself (exact Fourier shifts peak at a0), while the full-band variance is shown to be pulled by aliasing
alone, beyond the microscope bound, with no interpolation at all.
"""

import numpy as np
import pytest

import lfproc
from conftest import SAMPLES
from lfproc.cli import build_parser
from lfproc.refocusing import slice_sharpness
from lfproc.simulate import fourier_refocus, plane_views

SWEEP_HALF, SWEEP_STEP = 0.03, 0.001

#: every tenth of a lens as fractional part, on both sides of a = 1 (photographic), and microscope a
PHOTOGRAPHIC = [round(i / 10 + 0.05 + (i % 2), 2) for i in range(10)]        # 0.05, 1.15, 0.25, 1.35, …
MICROSCOPE = [-0.25, -0.13, -0.05, 0.01, 0.03, 0.07, 0.12, 0.2]


def border(a_values, m):
    """Lenses at each edge that some view's shift leaves (and 3 more)."""
    return int(np.ceil(np.abs(a_values).max() * (m - 1) / 2)) + 3


def sweep(a0, half=SWEEP_HALF):
    return np.round(np.arange(a0 - half, a0 + half + SWEEP_STEP / 2, SWEEP_STEP), 9)


def sharpest(lf, a0, interpolation, half=SWEEP_HALF):
    a = sweep(a0, half)
    stack = lfproc.refocus(lf, a, interpolation=interpolation)
    m = np.asarray(getattr(lf, "views", lf)).shape[0]
    return float(a[int(np.argmax(slice_sharpness(stack, border(a, m))))])


def test_sharpness_measure_is_unbiased():
    """Exact shifts of a band-limited plane (no aliasing, no interpolation): the measure peaks at a0."""
    for a0 in (0.1, 0.5, 0.9):
        views = plane_views(9, 32, a0, seed=3, oversample=1, band=0.45)
        a = sweep(a0)
        found = a[int(np.argmax(slice_sharpness(fourier_refocus(views, a), border(a, 9))))]
        assert abs(found - a0) < 0.75 * SWEEP_STEP, (a0, found)


def test_full_band_sharpness_is_pulled_by_aliasing_without_any_interpolation():
    """Why the measure keeps to a quarter cycle per lens: on an aliased plane (lens integration, detail finer
    than a lens) even exact shifts put the peak of the full-band variance beyond the microscope bound —
    aliased detail comes into focus at other a — while the band's peak stays at a0."""
    a0 = -0.05
    views = plane_views(15, 64, a0, seed=2, exponent=1.5)
    a = sweep(a0)
    stack = fourier_refocus(views, a)
    inner = stack[:, border(a, 15):-border(a, 15), border(a, 15):-border(a, 15), 0]
    full = a[int(np.argmax(inner.reshape(len(a), -1).var(axis=1)))]
    band = a[int(np.argmax(slice_sharpness(stack, border(a, 15))))]
    assert abs(full - a0) > 0.005 and abs(band - a0) <= 0.002, (full, band)


def test_linear_interpolation_snaps_to_integer_a():
    """The bias this issue is about, and the reason the commands do not default to linear."""
    errors = [sharpest(plane_views(9, 48, a0, seed=1), a0, "linear") - a0 for a0 in (0.1, 0.9)]
    assert max(abs(e) for e in errors) > 0.02, errors
    assert errors[0] < 0 < errors[1]      # towards a = 0 and a = 1


@pytest.mark.parametrize("exponent", [1.5, 2.0, 3.0])
def test_photographic_sharpest_slice_within_0_01(exponent):
    errors = [sharpest(plane_views(9, 64, a0, seed=1, exponent=exponent), a0, "cubic-spline") - a0
              for a0 in PHOTOGRAPHIC]
    assert max(abs(e) for e in errors) <= 0.01 + 1e-9, dict(zip(PHOTOGRAPHIC, np.round(errors, 4)))


@pytest.mark.parametrize("exponent", [1.5, 2.0, 3.0])
def test_microscope_sharpest_slice_within_0_005(exponent):
    errors = [sharpest(plane_views(15, 64, a0, seed=2, exponent=exponent), a0, "cubic-spline", half=0.02) - a0
              for a0 in MICROSCOPE]
    assert max(abs(e) for e in errors) <= 0.005 + 1e-9, dict(zip(MICROSCOPE, np.round(errors, 4)))


def test_simulator_renders_of_the_sample_camera_within_0_01():
    """The photographic simulator's views of the bundled sample camera (11 × 11 views at f/4, only the
    views wholly inside the stop averaged) of a value-noise plane at the distance of each slice a0, its
    texture scaled with the distance (2 mm features at the distance of a = 0.9) so that it has the same
    size in lenses at every a0. (A fixed 2 mm texture at the distance of a = 0.1, 5.8 m, is finer than the
    lenses resolve: exact shifts already put its sharpest slice 0.022 off; docs/microscope-imaging.md.)"""
    from dataclasses import replace

    from lfproc import Camera, geometry
    from lfproc.simulate import Noise, Plane, Scene, render_ideal_views

    camera = replace(Camera.from_toml(str(SAMPLES / "sample" / "camera.toml")), cfa="none")
    m = camera.m_hat
    values = (0.1, 0.25, 0.4, 0.6, 0.75, 0.9, 1.1, 1.3, 1.5, 1.7, 1.9)
    errors = []
    scale = 2.0 / float(geometry.slice_distance_mm(camera, 0.9))
    for a0 in values:
        distance = float(geometry.slice_distance_mm(camera, a0))
        scene = Scene([Plane(distance, Noise(feature_mm=scale * distance, seed=3))])
        views, weight, _ = render_ideal_views(camera, scene, (11 * 48, 11 * 48), pixel_samples=2,
                                              aperture_samples=2, channels=1)
        lf = lfproc.LightField.from_views(views, view_mask=weight.reshape(m, m, -1).min(axis=2) > 0.999)
        errors.append(sharpest(lf, a0, "cubic-spline", half=0.05) - a0)
    assert max(abs(e) for e in errors) <= 0.01 + 1e-9, dict(zip(values, np.round(errors, 4)))


@pytest.mark.parametrize("command", ["refocus", "batch"])
def test_commands_default_to_cubic_spline(command):
    parser = build_parser()
    args = parser.parse_args([command, "x.raw", "--camera", "c.toml", "--white", "w.tif", "--a", "0", "-o", "out"])
    assert args.interpolation == "cubic-spline"


def test_cubic_spline_is_the_spline_through_each_view():
    """Away from the borders a cubic-spline slice is the mean of the views' interpolating cubic splines
    (scipy.ndimage.map_coordinates, order 3), also upsampled; whole lenses are the lenses themselves."""
    from scipy import ndimage

    m, n = 5, 40
    views = np.random.default_rng(5).random((m, m, n, n, 1)).astype(np.float32)
    c = (m - 1) // 2
    for a, s in ((0.3, 1), (-0.55, 1), (0.7, 2)):
        out = lfproc.refocus(views, a, interpolation="cubic-spline", upsample=s)[..., 0]
        grid = np.arange((n - 1) * s + 1) / s
        expected = np.mean([ndimage.map_coordinates(views[ky, kx, :, :, 0].astype(np.float64),
                                                    np.meshgrid(grid + a * (c - ky), grid + a * (c - kx),
                                                                indexing="ij"), order=3, mode="mirror")
                            for ky in range(m) for kx in range(m)], axis=0)
        inner = slice(16 * s, -16 * s)                 # beyond the filter's reach from the border band
        np.testing.assert_allclose(out[inner, inner], expected[inner, inner], atol=2e-6)
    whole = lfproc.refocus(views, [1.0, 0.5], interpolation="cubic-spline")
    assert np.array_equal(whole[0], lfproc.refocus(views, 1.0, interpolation="nearest"))


def test_cubic_sharp_is_an_interpolation():
    """Keys' kernel with a = −0.9 reproduces the lenses at whole positions and a linear ramp between them."""
    ramp = np.broadcast_to(np.arange(20, dtype=np.float32)[None, :, None], (20, 20, 1))
    views = np.broadcast_to(ramp, (3, 3, 20, 20, 1)).copy()
    out = lfproc.refocus(views, 0.3, interpolation="cubic-sharp")
    inner = out[3:-3, 3:-3, 0]
    assert np.allclose(inner, np.arange(20, dtype=np.float32)[3:-3][None, :], atol=1e-5)
    whole = lfproc.refocus(views, 1.0, interpolation="cubic-sharp")
    assert np.array_equal(whole, lfproc.refocus(views, 1.0, interpolation="nearest"))
