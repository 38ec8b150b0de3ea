"""A finite exit pupil end to end (issue 12): render → calibrate the white image → decode → refocus and views.

The micro images of a non-telecentric main lens sit outwards from their lenses (their lattice is the
lens lattice scaled by (d_A + f_s)/d_A). Calibration finds the micro image centres, decoding samples
around them, and the geometry with the exit pupil tags the slices: the slice that is sharpest over each
plane must carry a depth of field that holds the plane's true distance, and the views' parallax must be
the one the triangulation predicts. The telecentric model, given the same measured slices, misses.
"""

import dataclasses

import numpy as np
import pytest
from scipy import ndimage

from lfproc import Camera, geometry
from lfproc import simulate
from lfproc.io import write_image
from lfproc.api import prepare_decoding
from lfproc.refocusing import refocus
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens
from plainref import measured_shift

EXIT_PUPIL_MM = 45.0
CAMERA = Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0, exit_pupil_distance_mm=EXIT_PUPIL_MM), black_level=64, white_level=16383, name="exit-pupil")
PLANE_A = (1.6, 0.7)          # the slices (of the finite-pupil model) the two planes sit at


@pytest.fixture(scope="module")
def decoded(tmp_path_factory):
    near, far = (float(d) for d in geometry.slice_distance_mm(CAMERA, PLANE_A))
    scene = Scene((Plane(near, Noise(feature_mm=2.5, seed=3, low=0.15, high=0.9), region_mm=(-40, 0, -60, 60)),
                   Plane(far, Noise(feature_mm=5.0, seed=4, low=0.1, high=0.9))), background=0.05)
    sim = simulate.render(CAMERA, scene, (440, 550), rotation_deg=0.2, offset_px=(0.3, -0.2), pixel_samples=2,
                          aperture_samples=4, shot_noise_photons=300000, seed=5, ideal_views=False)
    folder = tmp_path_factory.mktemp("exit_pupil")
    write_image(folder / "capture.png", sim.raw)
    write_image(folder / "white.png", sim.white)
    setup = prepare_decoding(CAMERA, white=str(folder / "white.png"), cache=True)        # calibrates the white image
    lf = setup.decode(str(folder / "capture.png"))
    return dict(sim=sim, lf=lf, grid=setup.grid, distances=(near, far))


def test_the_render_shows_the_outward_drift_and_calibration_finds_it(decoded):
    sim, grid = decoded["sim"], decoded["grid"]
    scale = geometry.micro_image_scale(CAMERA)
    assert scale == pytest.approx((EXIT_PUPIL_MM + CAMERA.mla_focal_length_mm) / EXIT_PUPIL_MM)
    assert grid.pitch_px == pytest.approx(CAMERA.pitch_px * scale, rel=2e-4)       # micro image pitch, not lens
    assert sim.grid.pitch_px / sim.lens_grid.pitch_px == pytest.approx(scale, rel=1e-9)
    # the outermost micro images sit several pixels outward from their lenses
    drift = np.abs(sim.grid.centers_xy_px() - sim.lens_grid.centers_xy_px()).max()
    assert drift > 2.0


def decoded_labels(sim, lf):
    """The simulator's plane label of each decoded lens: the rendered lens nearest to its fitted centre
    (decoding crops partial lenses, so the decoded lens indices start elsewhere)."""
    from scipy.spatial import cKDTree

    truth = sim.grid.centers_xy_px().reshape(-1, 2)
    distance, index = cKDTree(truth).query(lf.grid.centers_xy_px().reshape(-1, 2))
    found = distance < 0.2               # decoded lenses are rendered ones, found to a fraction of a pixel
    assert found.mean() > 0.95
    return np.where(found, sim.plane_label.reshape(-1)[index], -2).reshape(lf.lens_shape)


def plane_regions(sim, lf, erode=4):
    """Per plane, the lenses of the decoded grid whose central view sees it, off occlusion edges and borders."""
    labels = decoded_labels(sim, lf)
    regions = []
    for index in range(2):
        region = ndimage.binary_erosion(labels == index, iterations=erode)
        region[:erode] = region[-erode:] = False
        region[:, :erode] = region[:, -erode:] = False
        regions.append(region)
    return regions


def sharpest_a(lf, region, a_values):
    stack = refocus(lf, a_values, interpolation="cubic")
    energy = []
    for image in stack[..., 0] if stack.shape[-1] == 1 else stack.mean(axis=-1):
        gy, gx = np.gradient(image)
        energy.append(float(np.mean((gx ** 2 + gy ** 2)[region])))
    k = int(np.argmax(energy))
    e0, e1, e2 = energy[max(k - 1, 0)], energy[k], energy[min(k + 1, len(energy) - 1)]
    step = a_values[1] - a_values[0]
    return a_values[k] + (0.5 * step * (e0 - e2) / (e0 - 2 * e1 + e2) if 0 < k < len(energy) - 1 else 0.0)


def test_sharpest_slice_over_each_plane_has_a_dof_holding_its_distance_and_telecentric_misses(decoded):
    sim, lf = decoded["sim"], decoded["lf"]
    telecentric = CAMERA.with_optics(dataclasses.replace(CAMERA.main_optics, exit_pupil_distance_mm=float("inf")))
    a_values = np.round(np.arange(0.2, 2.41, 0.05), 10)
    for region, truth in zip(plane_regions(sim, lf), decoded["distances"]):
        assert region.sum() > 40
        a = sharpest_a(lf, region, a_values)
        geo = geometry.slice_geometry(CAMERA, [a])
        assert geo.near_mm[0] <= truth <= geo.far_mm[0], (a, truth, geo.near_mm[0], geo.far_mm[0])
        tele = geometry.slice_geometry(telecentric, [a])
        miss = abs(float(tele.distance_mm[0]) - truth)
        error = abs(float(geo.distance_mm[0]) - truth)
        print(f"plane {truth:.1f} mm: sharpest a={a:.3f}; exit-pupil model {float(geo.distance_mm[0]):.1f} mm "
              f"[{geo.near_mm[0]:.1f}, {geo.far_mm[0]:.1f}], telecentric model {float(tele.distance_mm[0]):.1f} mm "
              f"(misses by {miss:.1f} mm = {100 * miss / truth:.1f} %)")
        # the telecentric model, given the same measured slice, is off by several times the finite model's error
        assert miss > 5 * error and miss > 0.03 * truth


def test_views_parallax_matches_the_triangulation(decoded):
    """Over the far plane (it fills the right half), two views G apart see it shifted by what the model says."""
    sim, lf = decoded["sim"], decoded["lf"]
    far = decoded["distances"][1]
    c, gap = lf.center_index, 2
    region = plane_regions(sim, lf)[1]
    rows = np.flatnonzero(region.any(axis=1))
    cols = np.flatnonzero(region.all(axis=0) if region.all(axis=0).any() else region.any(axis=0))
    rows, cols = slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1)
    luma = lf.views.mean(axis=-1)
    first = luma[c, c - gap // 2, rows, cols].astype(np.float64)
    second = luma[c, c + gap // 2, rows, cols].astype(np.float64)
    dx = measured_shift(first, second)
    expected = -float(geometry.refocus_parameter(CAMERA, far)) * gap
    assert dx == pytest.approx(expected, abs=0.1)
    z = float(geometry.triangulate(CAMERA, dx, gap).distance_mm)
    lo, hi = sorted(float(d) for d in geometry.triangulate(CAMERA, [dx - 0.1, dx + 0.1], gap).distance_mm)
    assert lo <= far <= hi, (z, far)
