"""Refocusing with per-view shifts (the sine condition of a high-NA objective): the general path equals the
kernels for Eq. 9's shifts, and on a light field rendered with the sine condition's parallax the aplanatic
slice at a0 is sharp where the paraxial one is not, the paraxial sweep peaking where paraxial_depth_error says."""

from pathlib import Path

import numpy as np
import pytest

from lfproc import LfprocError, LightField
from lfproc import geometry as g
from lfproc.camera import Camera
from lfproc.refocusing import refocus

SAMPLES = Path(__file__).resolve().parents[1] / "lfproc" / "samples" / "cameras"
LFM60 = Camera.from_toml(SAMPLES / "lfm-60x-water.toml")


def _eq9_table(m):
    c = (m - 1) // 2
    k = np.arange(m, dtype=np.float64)
    return np.repeat((c - k)[:, None], m, axis=1), np.repeat((c - k)[None, :], m, axis=0)


@pytest.mark.parametrize("interpolation", ["nearest", "linear", "cubic", "cubic-spline"])
@pytest.mark.parametrize("upsample", [1, 3])
def test_per_view_table_of_eq9_equals_the_kernels(interpolation, upsample):
    rng = np.random.default_rng(3)
    views = rng.random((5, 5, 11, 13, 2)).astype(np.float32)
    a = [0.0, 0.37, -1.5, 2.0, 0.9]
    expected = refocus(views, a, interpolation, upsample)
    got = refocus(views, a, interpolation, upsample, view_shifts=_eq9_table(5))
    assert got.shape == expected.shape and np.abs(got - expected).max() < 1e-5


def test_masked_views_are_left_out_of_the_mean():
    rng = np.random.default_rng(4)
    views = rng.random((5, 5, 9, 9, 1)).astype(np.float32)
    mask = np.zeros((5, 5), bool)
    mask[1:4, 1:4] = True
    views[~mask] = 0.0
    lf = LightField.from_views(views, view_mask=mask)
    expected = refocus(lf, [0.5, 1.0])
    got = refocus(lf, [0.5, 1.0], view_shifts=_eq9_table(5))
    assert np.abs(got - expected).max() < 1e-5


def test_bad_tables_are_one_line_errors():
    views = np.zeros((3, 3, 4, 4, 1), np.float32)
    with pytest.raises(LfprocError, match=r"two finite \(3, 3\) arrays"):
        refocus(views, 0.5, view_shifts=(np.zeros((2, 2)), np.zeros((2, 2))))
    with pytest.raises(LfprocError, match="view_shifts"):
        refocus(views, 0.5, view_shifts=5)


def _sine_condition_light_field(camera, a0, size=48):
    """Views of a smooth texture on the plane z(a0): view k shows it shifted by −a0·σ_k (the sine condition)."""
    sigma_y, sigma_x = g.refocus_slopes(camera, aplanatic=True)
    m = camera.m_hat
    jy, jx = np.mgrid[0:size, 0:size].astype(np.float64)
    texture = lambda y, x: np.sin(2 * np.pi * x / 9.0) * np.cos(2 * np.pi * y / 11.0) + 0.3 * np.sin(2 * np.pi * (x + y) / 7.0)
    views = np.empty((m, m, size, size, 1), np.float32)
    for ky in range(m):
        for kx in range(m):
            views[ky, kx, :, :, 0] = texture(jy - a0 * sigma_y[ky, kx], jx - a0 * sigma_x[ky, kx])
    mask = g.views_inside_aperture(camera)
    views[~mask] = 0.0
    return LightField.from_views(views, camera=camera, view_mask=mask), texture(jy, jx)


def test_aplanatic_slice_is_the_plane_its_z_names():
    a0 = 0.6
    lf, truth = _sine_condition_light_field(LFM60, a0)
    assert g.uses_aplanatic(LFM60) and lf.refocus_slopes is not None
    inner = (slice(12, -12), slice(12, -12))
    aplanatic = refocus(lf, a0, interpolation="cubic")[..., 0]           # the light field's own table
    paraxial = refocus(lf.views, a0, interpolation="cubic")[..., 0] * (LFM60.m_hat ** 2 / lf.view_mask.sum())
    err_apl = np.abs(aplanatic - truth)[inner].max()
    err_par = np.abs(paraxial - truth)[inner].max()
    assert err_apl < 0.05 < err_par, (err_apl, err_par)


def test_paraxial_sweep_peaks_where_the_paraxial_error_says():
    a0 = 0.5
    lf, truth = _sine_condition_light_field(LFM60, a0)
    inner = (slice(12, -12), slice(12, -12))
    sweep = np.linspace(0.3, 1.2, 91)
    plain = LightField.from_views(lf.views, view_mask=lf.view_mask)              # no camera: Eq. 9 shifts
    stack = refocus(plain, sweep, interpolation="cubic")[..., 0]
    contrast = [s[inner].var() for s in stack]
    a_best = sweep[int(np.argmax(contrast))]
    predicted = a0 * (1.0 + g.paraxial_depth_error(LFM60))   # the paraxial slice tagged z·(1 + e) is sharpest
    assert abs(a_best - predicted) <= 0.05 * predicted, (a_best, predicted)
    assert abs(a_best - a0) > 0.2                              # and far from the true a0: the paraxial map is off
    fine = np.linspace(0.4, 0.6, 21)
    sharp = [s[inner].var() for s in refocus(lf, fine, interpolation="cubic")[..., 0]]
    assert fine[int(np.argmax(sharp))] == pytest.approx(a0, abs=0.011)   # aplanatic: sharpest at the true a0
