"""The depth map's fast half apertures (issue 24) give what the straightforward computation gives.

The fast path refocuses each half aperture from its own views only (``refocusing/_block.py``), counts the
views' weights from the sampling plans, aggregates edge-aware by one gather and computes the defocus cue
only at the lenses where a half can still win. The references here are the straightforward versions of
each: one fused refocus of ``w``, ``w·Y``, ``w·Y²`` over every view per axis, the edge-aware box chosen by
copying the whole volume per shift, and the defocus cue at every lens of the image, on a small render
with image borders and a near card (occlusions), where the half apertures decide many lenses.
"""

import numpy as np
import pytest
from test_depth_edges import SHAPE, camera, scene_for

import lfproc
from lfproc import geometry, simulate
from lfproc.depth import _estimate
from lfproc.depth._confidence import confidence, cost_floor
from lfproc.depth._cost import delivered_views, half_aperture_volumes, sweep_luminance
from lfproc.depth._estimate import central_texture
from lfproc.depth._refine import aggregate, refine_minimum
from lfproc.lightfield import LightField


@pytest.fixture(scope="module")
def light_field():
    cam = camera("none")
    sim = simulate.render(cam, scene_for(cam), SHAPE, rotation_deg=0.2, offset_px=(0.3, 0.1),
                          shot_noise_photons=200000, seed=3, ideal_views=True)
    return LightField.from_views(sim.ideal_views, cam, sim.grid)


def box_edge_aware(cost, window=5):
    """The edge-aware 5 × 5 box as first written: the whole volume shifted and selected per shift."""
    centred = aggregate(cost, window)
    h = window // 2
    best, best_min = centred, centred.min(axis=0)
    for axis, step in ((1, h), (1, -h), (2, h), (2, -h)):
        index = np.clip(np.arange(cost.shape[axis]) + step, 0, cost.shape[axis] - 1)
        shifted = np.take(centred, index, axis=axis)
        better = shifted.min(axis=0) < best_min
        best = np.where(better[None], shifted, best)
        best_min = np.where(better, shifted.min(axis=0), best_min)
    return best


def sharpest_slice(luminance, a_values):
    """The defocus cue at every lens: largest 5 × 5 gradient energy, refined like the correspondence cost."""
    energy = np.zeros_like(luminance)
    for axis in (1, 2):
        d = np.diff(luminance, axis=axis) ** 2
        energy[(slice(None),) * axis + (slice(1, None),)] += d
        energy[(slice(None),) * axis + (slice(None, -1),)] += d
    energy = aggregate(energy)
    return refine_minimum(energy.max() - energy, a_values, 0.0).a


def straightforward_best_of_half_apertures(all_views):
    def best_of(sweep, a_values, interpolation, volume, minimum, conf, center_index, bin_lenses=1):
        floor, textured, best = cost_floor(volume.luminance), central_texture(sweep, bin_lenses), minimum
        for half in half_aperture_volumes(sweep, a_values, interpolation=interpolation, bin_lenses=bin_lenses,
                                          all_views=all_views):
            finite = np.isfinite(half.cost)
            cost = np.where(finite, half.cost, np.float32(10.0 * float(half.cost[finite].max()) + 1.0))
            found = refine_minimum(box_edge_aware(cost), a_values, floor)
            lum = np.where(np.isfinite(half.luminance), half.luminance, volume.luminance)
            conf_half = confidence(found.a, found.a_low, found.a_high, sharpest_slice(lum, a_values), center_index,
                                   resolution=bin_lenses)
            take = np.where(found.interior & finite.all(axis=0) & textured, conf_half, np.float32(0.0)) > conf
            best = found.where(take, best)
            conf = np.where(take, conf_half, conf)
        return best, conf
    return best_of


@pytest.mark.parametrize("view_step, interpolation, bin_lenses", [(1, "cubic", 1), (2, "linear", 2)])
def test_each_halfs_own_views_give_the_all_view_volumes(light_field, view_step, interpolation, bin_lenses):
    weight = delivered_views(light_field.views) & geometry.views_inside_aperture(light_field.camera)
    c = (weight.shape[0] - 1) // 2
    weight[c - 1, c + 2] = weight[c + 2, c] = False        # holes inside the halves: their weights count
    sweep = sweep_luminance(light_field.views, view_step, c - 1, weight)
    a = np.round(np.arange(0.0, 2.8, 0.1), 10)
    fast = half_aperture_volumes(sweep, a, interpolation=interpolation, bin_lenses=bin_lenses)
    reference = half_aperture_volumes(sweep, a, interpolation=interpolation, bin_lenses=bin_lenses, all_views=True)
    for got, want in zip(fast, reference, strict=True):
        whole = np.isfinite(want.cost)
        assert 0.3 < whole.mean() < 1.0                  # the border takes lenses out of every half
        np.testing.assert_array_equal(np.isfinite(got.cost), whole)
        np.testing.assert_allclose(got.cost[whole], want.cost[whole], rtol=0, atol=1e-5 * want.cost[whole].max())
        np.testing.assert_allclose(got.luminance[whole], want.luminance[whole], rtol=0, atol=1e-6)


def test_fast_half_apertures_give_the_straightforward_depth_map(light_field, monkeypatch):
    fast = lfproc.depth_map(light_field)
    monkeypatch.setattr(_estimate, "best_of_half_apertures", straightforward_best_of_half_apertures(False))
    reference = lfproc.depth_map(light_field)
    monkeypatch.setattr(_estimate, "best_of_half_apertures", straightforward_best_of_half_apertures(True))
    all_views = lfproc.depth_map(light_field)
    without = lfproc.depth_map(light_field, half_apertures=False)
    # the half apertures decide many lenses here (borders, the card's occlusion edges), confident ones included
    decided = fast.confidence != without.confidence
    assert decided.sum() > 100 and (decided & (without.confidence >= 0.5)).any()
    # the same volumes: bitwise the same map (a lens the defocus cue skipped that a half could win would differ)
    for field in ("a", "confidence", "distance_mm", "near_mm", "far_mm", "allfocus"):
        np.testing.assert_array_equal(getattr(fast, field), getattr(reference, field), err_msg=field)
    # the volumes over all views differ by float rounding: the same map but for the odd tie between slices
    same = (np.isnan(fast.a) & np.isnan(all_views.a)) | (np.abs(fast.a - all_views.a) <= 1e-4)
    assert same.mean() >= 0.995
