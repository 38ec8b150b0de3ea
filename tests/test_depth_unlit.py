"""Issue 30: no depth without light. On a real capture whose right edge was black (1-8 DN) all 54 unlit lenses got
a depth at confidence 0.95-0.98; here a render whose right third is as dark (1 % of the level, with noise) must
leave every unlit lens unknown (NaN, confidence 0) in the depth map and the viewer's depth, while the lit part
keeps its depth."""

import numpy as np
import pytest

import lfproc
from lfproc import geometry, simulate
from lfproc.camera import Camera, MainLens
from lfproc.decode import make_decoder
from lfproc.lightfield import LightField
from lfproc.simulate import Noise, Plane, Scene

CAM = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), name="unlit-test")


@pytest.fixture(scope="module")
def dark_edge():
    distance = float(geometry.slice_distance_mm(CAM, 0.8))
    sim = simulate.render(CAM, Scene((Plane(distance, Noise(feature_mm=3.0, seed=2, low=0.2, high=0.9)),)),
                          (240, 330), shot_noise_photons=20000, seed=5, ideal_views=False)
    raw = sim.raw.astype(np.float64) / np.iinfo(sim.raw.dtype).max if sim.raw.dtype.kind == "u" else sim.raw.astype(float)
    white = sim.white.astype(np.float64)
    white = white / white.max()
    dark_from = int(raw.shape[1] * 2 / 3)
    rng = np.random.default_rng(1)
    raw[:, dark_from:] = 0.01 * raw[:, dark_from:] + rng.normal(0, 0.003, raw[:, dark_from:].shape)  # 1-8 DN of 255
    decoder = make_decoder(white, sim.grid, CAM.m_hat, "none")
    lf = LightField.from_views(decoder(raw, "none"), CAM, decoder.output_grid, decoder.views_delivered,
                               decoder.view_centre)
    xs = sim.grid.lens_xy(np.zeros(sim.grid.cols, int), np.arange(sim.grid.cols))[:, 0]
    columns = decoder.output_grid.cols
    unlit = np.zeros(lf.lens_shape, bool)
    unlit[:, xs[:columns] > dark_from + CAM.pitch_px] = True       # lenses wholly in the dark part
    lit = np.zeros(lf.lens_shape, bool)
    lit[:, xs[:columns] < dark_from - 3 * CAM.pitch_px] = True
    return lf, unlit, lit


def test_unlit_lenses_carry_no_depth_and_lit_ones_keep_theirs(dark_edge):
    from lfproc.depth import lit_lenses

    lf, unlit, lit = dark_edge
    assert unlit.sum() >= 100 and lit.sum() >= 100
    assert not lit_lenses(lf.views, lf.view_mask)[unlit].any()
    result = lfproc.depth_map(lf)
    assert np.all(np.isnan(result.a[unlit])) and np.all(np.isnan(result.distance_mm[unlit]))
    assert np.all(result.confidence[unlit] == 0.0)
    assert np.mean(np.isfinite(result.a[lit])) > 0.5              # the lit part keeps its depth
    from lfproc.viewer._estimate import estimate_depth
    focus = estimate_depth(lf, depth_map=result)
    assert np.all(np.isnan(focus.a[unlit])) and np.all(focus.confidence[unlit] == 0.0)
