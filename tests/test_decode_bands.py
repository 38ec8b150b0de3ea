"""The decode does not depend on memory tuning (issue 31): the read plan's bands (``lfproc.decode._plan``).

References: the simulator's known radiance (a tinted flat plane: true channel means), and the same
capture decoded in one band. The old decoder lost rim-aware decoding in bands too tall for one remap
(a 12000 × 72 px RGGB capture decoded 7 % too dark: 0.670/0.230/0.0745 for 0.72/0.24/0.08), and its
float32 maps put sample rows a few 1e-4 px apart for different band splits.
"""

import numpy as np
import pytest

from lfproc import Camera, geometry, simulate
from lfproc.decode import _plan, make_decoder
from lfproc.simulate import Plane, Scene, Uniform
from lfproc.camera import MainLens

TRUE_RGB = (0.72, 0.24, 0.08)     # Uniform(0.8) tinted (0.9, 0.3, 0.1)


def camera(cfa="RGGB"):
    return Camera(0.005, 0.06, 0.24, MainLens(50.0, 50.0, f_number=4.0), grid="rectangular", cfa=cfa, black_level=0, white_level=65535)


def flat_capture(shape, cfa="RGGB"):
    cam = camera(cfa)
    d = geometry.slice_distance_mm(cam, 1.0)
    sim = simulate.render(cam, Scene((Plane(d, Uniform(0.8), tint=(0.9, 0.3, 0.1)),), background=0.1), shape,
                          rim_radius_mm=None, pixel_samples=1, aperture_samples=2, seed=2, ideal_views=False)
    scale = np.float32(1.0 / (65535 * 0.8))
    return cam, sim.grid, sim.raw.astype(np.float32) * scale, sim.white.astype(np.float32) * scale


def decoded(cam, grid, raw, white, monkeypatch, band_bytes):
    monkeypatch.setattr(_plan, "BAND_BYTES", band_bytes)
    decoder = make_decoder(white, grid, cam.m_hat, cam.cfa)
    return decoder, decoder(raw)


def channel_means(decoder, views):
    inner = views[decoder.views_delivered][:, 1:-1, 1:-1]
    return inner.reshape(-1, views.shape[-1]).mean(axis=0)


@pytest.mark.parametrize("shape", [(12000, 72), (72, 12000)])
def test_a_very_tall_or_wide_sensor_decodes_its_true_radiance_in_any_bands(shape, monkeypatch):
    cam, grid, raw, white = flat_capture(shape)
    decoder, views = decoded(cam, grid, raw, white, monkeypatch, _plan.BAND_BYTES)
    if shape[0] > shape[1]:     # the default band reads every lens: the plan must split it to fit one remap
        assert len(decoder.read_plan.bands) > 1
    np.testing.assert_allclose(channel_means(decoder, views), TRUE_RGB, rtol=0.01)
    one_band = 10 * 2**30       # every lens row in one planned band (split only where remap needs it)
    small = 1                   # two lens rows a band
    for band_bytes in (one_band, small):
        other, again = decoded(cam, grid, raw, white, monkeypatch, band_bytes)
        assert np.array_equal(other.inverse_white, decoder.inverse_white)
        assert np.array_equal(again, views)


@pytest.mark.parametrize("cfa, method, tolerance", [("RGGB", "fast", 0.1), ("RGGB", "careful", 0.1),
                                                    ("none", "fast", 0.1), ("RGGB", "fast", None)])
def test_the_decode_is_bit_identical_for_any_band_size(cfa, method, tolerance, monkeypatch):
    """The bundled sample's case: views were up to 6e-4 apart between one band and two lens rows a band."""
    cam = camera(cfa)
    d = geometry.slice_distance_mm(cam, 1.0)
    feature = 4 * cam.mla_pitch_mm * (d - cam.main_optics.sensor_path_mm(cam.mla_path_mm)) / cam.main_optics.focal_length_mm
    sim = simulate.render(cam, Scene((Plane(d, simulate.Noise(feature_mm=feature, seed=3), tint=(0.9, 0.7, 0.5)),),
                                     background=0.1), (300, 260), rotation_deg=-0.4, rim_radius_mm=None,
                          pixel_samples=1, aperture_samples=2, seed=2, ideal_views=False)
    raw, white = sim.raw.astype(np.float32) / 52428, sim.white.astype(np.float32) / 52428
    results = []
    for band_bytes in (10 * 2**30, 100_000, 1):
        monkeypatch.setattr(_plan, "BAND_BYTES", band_bytes)
        decoder = make_decoder(white, sim.grid, cam.m_hat, cfa, demosaic_method=method,
                               centroid_tolerance=tolerance)
        results.append((len(decoder.read_plan.bands), decoder.inverse_white, decoder(raw)))
    assert results[0][0] < results[1][0] < results[2][0]
    assert results[0][2][decoder.views_delivered].mean() > 0.1
    for count, inverse, views in results[1:]:
        assert np.array_equal(inverse, results[0][1])
        assert np.array_equal(views, results[0][2])
