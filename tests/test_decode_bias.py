"""Issue 13's systematic refocus bias: a fine sweep over a peaks at the true a of a rendered plane.

The focus measure is independent of lfproc's refocusing: shift-and-sum with scipy's order-5 spline
interpolation (linear interpolation pulls the peak towards integer a, 1.93 -> 2.00, see lfproc.decode),
checked here on views that are exact shifts of one texture. The truth is the plane's a from the geometry
(``refocus_parameter`` of its distance), not from the decoder.
"""

import numpy as np
import pytest
from scipy import ndimage

from lfproc import Camera, geometry, simulate
from lfproc.decode import make_decoder
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

A_TRUE = 1.93


def sharpness(views, a_values, delivered=None):
    """Gradient energy of the spline shift-and-sum slice of each a, away from the border band."""
    m = views.shape[0]
    c = (m - 1) // 2
    luma = views.mean(axis=-1).astype(np.float64)
    border = int(np.ceil(max(abs(a) for a in a_values) * c)) + 2
    coeffs = {(ky, kx): ndimage.spline_filter(luma[ky, kx], order=5) for ky in range(m) for kx in range(m)
              if delivered is None or delivered[ky, kx]}
    scores = []
    for a in a_values:
        total = sum(ndimage.shift(cf, (-a * (c - ky), -a * (c - kx)), order=5, prefilter=False, mode="mirror")
                    for (ky, kx), cf in coeffs.items())
        inner = total[border:-border, border:-border]
        scores.append(np.mean(np.diff(inner, axis=0) ** 2) + np.mean(np.diff(inner, axis=1) ** 2))
    return np.array(scores)


def sweep_peak(views, centre, delivered=None, half_width=0.08, step=0.01):
    a_values = np.arange(centre - half_width, centre + half_width + step / 2, step)
    s = sharpness(views, a_values, delivered)
    i = int(np.argmax(s))
    assert 0 < i < len(s) - 1, "the sweep's peak lies at its end: widen it"
    s0, s1, s2 = s[i - 1:i + 2]
    return a_values[i] + 0.5 * step * (s0 - s2) / (s0 - 2 * s1 + s2)


def test_the_focus_measure_is_unbiased_on_exactly_shifted_views():
    m, c, ny, nx = 11, 5, 44, 54
    rng = np.random.default_rng(0)
    texture = ndimage.gaussian_filter(rng.normal(size=(3 * ny, 3 * nx)), 1.5)
    yy, xx = np.mgrid[0:ny, 0:nx].astype(float)
    views = np.empty((m, m, ny, nx, 1))
    for ky in range(m):
        for kx in range(m):   # view k at lens j shows the texture point j - a(c - k) (refocus contract)
            views[ky, kx, :, :, 0] = ndimage.map_coordinates(texture, [yy + ny - A_TRUE * (c - ky),
                                                                       xx + nx - A_TRUE * (c - kx)], order=5)
    assert sweep_peak(views, A_TRUE) == pytest.approx(A_TRUE, abs=0.003)


def render(kind, cfa):
    """A textured plane at the true a, 12 px lenses (14 px hexagonal), f-number matched, rotated lattice."""
    pitch_mm = 0.06 if kind == "rectangular" else 0.07
    cam = Camera(0.005, pitch_mm, 0.24, MainLens(50.0, 50.0, f_number=4.0), grid=kind, cfa=cfa, black_level=0, white_level=65535)
    distance = geometry.slice_distance_mm(cam, A_TRUE)
    a_true = geometry.refocus_parameter(cam, distance)     # the geometry's truth for that plane
    feature = 3 * cam.mla_pitch_mm * (distance - cam.main_optics.sensor_path_mm(cam.mla_path_mm)) / cam.main_optics.focal_length_mm
    scene = Scene((Plane(distance, Noise(feature_mm=feature, seed=1)),), background=0.1)
    sim = simulate.render(cam, scene, (600, 720), rotation_deg=-0.4, rim_radius_mm=None, pixel_samples=3,
                          aperture_samples=3, seed=1, ideal_views=False)
    scale = np.float32(1.0 / 65535)
    return cam, a_true, sim.raw.astype(np.float32) * scale, sim.white.astype(np.float32) * scale, sim.grid


@pytest.mark.parametrize("kind", ["rectangular", "hexagonal"])
@pytest.mark.parametrize("cfa", ["RGGB", "none"])
def test_a_fine_sweep_over_a_decoded_capture_peaks_at_the_true_a(kind, cfa):
    cam, a_true, raw, white, grid = render(kind, cfa)
    decoder = make_decoder(white, grid, cam.m_hat, cfa)
    views = decoder(raw)
    assert sweep_peak(views, a_true, decoder.views_delivered) == pytest.approx(a_true, abs=0.01)
    # ... with the views inside the main lens aperture won back (issue 20): 45 of 97 were delivered on
    # rectangular RGGB, 69 mono; 89 now on each (Bayer: rim-aware demosaicing, lfproc.decode._rim_demosaic)
    delivered = decoder.views_delivered
    inside = geometry.views_inside_aperture(cam)
    assert not np.any(delivered & ~inside)
    assert np.array_equal(delivered, delivered[::-1]) and np.array_equal(delivered, delivered[:, ::-1])
    assert delivered.sum() >= 0.9 * inside.sum()
    if cfa == "RGGB":   # every channel on its own stands for the pixel's ray (bilinear R and B read inwards)
        for ch in range(3):
            assert sweep_peak(views[..., ch:ch + 1], a_true, delivered) == pytest.approx(a_true, abs=0.01)
    # the same capture with every lit view delivered (the old decoder) is biased towards far focus: this
    # is what the test guards against (measured: 1.76 for rectangular RGGB)
    if kind == "rectangular" and cfa == "RGGB":
        everything = make_decoder(white, grid, cam.m_hat, cfa, centroid_tolerance=None)
        assert sweep_peak(everything(raw), a_true - 0.15, half_width=0.15) < a_true - 0.05
