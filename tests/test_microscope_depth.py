"""Depth maps of a high-NA microscope are exact in z (issue 21): the depth sweep refocuses with the same
per-view sine-condition shifts as refocusing does, so the sweep's sharpest slice a is the plane z(a).

Ground truth: the LFM simulator's 60x/1.2 water objective (rays by the Abbe sine condition, exact at any NA)
with one textured fluorescent sheet at a known depth. Before, the sweep refocused paraxially and divided
its a by one factor 1 + e (e the paraxial error averaged over the views): a sheet at z(0.6) came out
0.41 of a DOF too shallow and one at z(−0.5) 0.36 of a DOF too shallow on the other side.
"""

import numpy as np
import pytest

import lfproc
from lfproc import LightField, geometry
from lfproc.simulate import MicroscopeScene, Sheet, render_microscope_views

from test_microscope_imaging_sim import LFM_60X


@pytest.mark.parametrize("a_true", [0.6, -0.5])
def test_depth_of_a_textured_sheet_at_na_1_2(a_true):
    camera = LFM_60X
    assert geometry.uses_aplanatic(camera)
    lat, zpa = camera.main_optics.lateral_sampling_um(camera), geometry.z_per_a_um(camera)
    sheet = Sheet(z_um=a_true * zpa, period_um=4.0 * lat, seed=3)
    views, _ = render_microscope_views(camera, MicroscopeScene(sheets=(sheet,)), (24, 24), pixel_samples=2,
                                       aperture_samples=2)
    # every estimate (min_confidence 0): the question is where the sweep's minimum sits, not how sure it is
    depth = lfproc.depth_map(LightField.from_views(views, camera), min_confidence=0.0)
    inner = depth.z_um[5:-5, 5:-5]
    dof = geometry.microscope_slices(camera, a_true).dof_um
    assert abs(float(np.median(inner)) - sheet.z_um) <= 0.1 * dof, (float(np.median(inner)), sheet.z_um, dof)
    # and the bounds hold the truth at most lenses
    near, far = depth.z_near_um[5:-5, 5:-5], depth.z_far_um[5:-5, 5:-5]
    assert np.mean((far <= sheet.z_um) & (sheet.z_um <= near)) >= 0.9
