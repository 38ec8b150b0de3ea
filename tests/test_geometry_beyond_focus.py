"""Slices beyond the focus distance (a < 0, issue 12): renders decide between the paper's DOF and ours,
and depth-range planning covers what it can (issue 14)."""

import math

import numpy as np
import pytest

from focus import focused
import lfproc
from lfproc import Camera, LfprocError
from lfproc import geometry as g

from lfproc import simulate  # noqa: E402
from lfproc.simulate import Noise, Plane, Scene  # noqa: E402
from lfproc.camera import MainLens

# Lytro-like, telecentric: 13 px micro images (c = 6), f/2 matched to the micro lenses, focused at 600 mm
LYTRO = focused(Camera(0.0014, 0.0182, 0.0364, MainLens(30.0, 30.0, f_number=2.0), micro_image_px=13), 600.0)
LENSES = 16


def views_of_plane_at(a_z):
    """Ideal views of a noise plane at slice a_z's depth, its texture scaled with the magnification
    (1.5 lens footprints per feature), so that every plane looks alike in focus."""
    d = g.slice_distance_mm(LYTRO, a_z)
    z = d - LYTRO.main_optics.sensor_path_mm(LYTRO.mla_path_mm)
    footprint = LYTRO.mla_pitch_mm * abs(1 - z / LYTRO.main_optics.focal_length_mm)
    views, _, _ = simulate.render_ideal_views(LYTRO, Scene((Plane(d, Noise(1.5 * footprint, seed=3)),)),
                                              (LENSES * 13, LENSES * 13), rim_radius_mm=None)
    return views


def energy(image, border=5):
    img = image[border:-border, border:-border, 0]
    return float((np.diff(img, axis=0) ** 2).mean() + (np.diff(img, axis=1) ** 2).mean())


@pytest.fixture(scope="module")
def renders():
    return {a_z: views_of_plane_at(a_z) for a_z in (-1.1, -1.0, -0.9, 0.0, 0.9, 1.0, 1.1)}


def paper_dof_a(a, c):
    """The 2014 paper's DOF limits in a, used for every a: (2ac - 1)/(2c + 1) and (2ac + 1)/(2c - 1)."""
    return (2 * a * c - 1) / (2 * c + 1), (2 * a * c + 1) / (2 * c - 1)


def test_a_view_is_as_blurred_beyond_the_focus_as_before_it(renders):
    """The paper's border-ray pair implies beams 1 + a lenses wide, i.e. a perfectly sharp view of a plane
    at a = -1. Beams that fill their micro lens and pixel are 1 + |a| wide: the same blur at a and -a."""
    c = LYTRO.center_index
    e = {a: energy(v[c, c]) for a, v in renders.items()}
    assert e[-1.0] == pytest.approx(e[1.0], rel=0.05)
    assert e[-1.0] < 0.9 * e[0.0]                       # not the sharpest: blurred like a = +1


def test_slice_at_minus_one_keeps_a_depth_of_field(renders):
    """Around slice a = -1 the refocused plane stays as sharp as around a = +1, where the paper's DOF
    spans [0.846, 1.182] in a; the paper predicts a zero DOF at -1, the bounding beams [-1.18, -0.85]."""
    c = LYTRO.center_index
    assert paper_dof_a(-1.0, c)[0] == pytest.approx(paper_dof_a(-1.0, c)[1])     # the singularity
    sharp = {}
    for a_s in (-1.0, 1.0):
        for step in (-0.1, 0.1):
            lf = lfproc.LightField.from_views(renders[round(a_s + step, 1)], LYTRO)
            peak = lfproc.LightField.from_views(renders[a_s], LYTRO)
            sharp[a_s, step] = (energy(lfproc.refocus(lf, a_s, interpolation="nearest"))
                                / energy(lfproc.refocus(peak, a_s, interpolation="nearest")))
    for step in (-0.1, 0.1):
        assert sharp[-1.0, step] > 0.5 and sharp[1.0, -step] > 0.5
        assert sharp[-1.0, step] == pytest.approx(sharp[1.0, -step], abs=0.1)
    for a_s in (-1.0, 1.0):   # and our model's DOF holds both neighbours
        geo = g.slice_geometry(LYTRO, a_s)
        for step in (-0.1, 0.1):
            assert geo.near_mm <= g.slice_distance_mm(LYTRO, a_s + step) <= geo.far_mm


def test_dof_grows_beyond_the_focus_distance():
    """The issue's complaint: the paper's DOF shrinks with distance beyond the focus (zero at a = -1)."""
    a = np.array([0.0, -0.5, -1.0, -1.5, -2.0, -3.0])
    geo = g.slice_geometry(LYTRO, a)
    assert np.all(np.diff(geo.distance_mm) > 0) and np.all(np.diff(geo.dof_mm) > 0)
    assert np.all(geo.dof_mm > 0)


def test_positive_a_in_front_of_the_focus_is_the_paper():
    c = LYTRO.center_index
    a = np.array([1.0 / (2 * c), 0.5, 1.0, 2.0, 4.0])
    geo = g.slice_geometry(LYTRO, a)
    lo, hi = paper_dof_a(a, c)
    np.testing.assert_array_equal(geo.near_mm, g.slice_distance_mm(LYTRO, hi))
    np.testing.assert_array_equal(geo.far_mm, g.slice_distance_mm(LYTRO, lo))


# ------------------------------------------------------------------ planning (issue 14)
ILLUM = focused(Camera(0.0014, 0.02, 0.0406, MainLens(77.59, 77.59, f_number=2.11, exit_pupil_distance_mm=46.05), grid="hexagonal", micro_image_px=13), 600.0)


def check_covers(cam, near, far, a):
    geo = g.slice_geometry(cam, a)
    assert math.isinf(geo.far_mm[0]) if math.isinf(far) else geo.far_mm[0] >= far
    assert geo.near_mm[-1] <= near and np.all(geo.far_mm[1:] >= geo.near_mm[:-1])


@pytest.mark.parametrize("cam", [ILLUM, LYTRO], ids=["illum", "lytro"])
@pytest.mark.parametrize("near, far", [(400.0, 2000.0), (300.0, math.inf)])
def test_depth_ranges_across_the_focus_distance_are_planned_whole(cam, near, far):
    plan = g.plan_depth_range(cam, near, far)
    assert plan.complete and 1 < len(plan.a) < 200
    check_covers(cam, near, far, plan.a)
    np.testing.assert_array_equal(plan.a, g.plan_slices(cam, near, far))


def test_a_plan_over_the_slice_limit_covers_the_far_part_and_names_the_rest():
    plan = g.plan_depth_range(ILLUM, 400.0, 2000.0, max_slices=5)
    assert len(plan.a) == 5 and not plan.complete
    (lo, hi, why), = plan.uncovered
    assert lo == 400.0 and 400.0 < hi < 2000.0 and "5 slices" in why
    check_covers(ILLUM, hi, 2000.0, plan.a)
    with pytest.raises(LfprocError, match="needs more than 5 slices"):
        g.plan_slices(ILLUM, 400.0, 2000.0, max_slices=5)
    assert g.MAX_SLICES >= 1000
    assert len(g.plan_depth_range(ILLUM, 400.0, 2000.0, max_slices=10 ** 6).a) == len(g.plan_slices(ILLUM, 400, 2000))


def test_depths_no_slice_can_reach_are_named_not_refused():
    closest = ILLUM.main_optics.sensor_path_mm(ILLUM.mla_path_mm) + ILLUM.main_optics.focal_length_mm
    plan = g.plan_depth_range(ILLUM, 50.0, 2000.0)
    assert len(plan.a) > 1
    reasons = " ".join(why for _, _, why in plan.uncovered)
    assert "front focal plane" in reasons and plan.uncovered[-1][0] == 50.0
    assert plan.uncovered[-1][1] == pytest.approx(closest, rel=1e-6)
    with pytest.raises(LfprocError, match="larger FAR"):
        g.plan_depth_range(ILLUM, 10.0, 20.0)


def test_allowed_gaps_are_listed_with_their_reason():
    plan = g.plan_depth_range(ILLUM, 400.0, 2000.0, integer=True)
    assert np.all(plan.a == np.round(plan.a))
    for lo, hi, why in plan.uncovered:
        assert 400.0 <= lo < hi <= 2000.0 and "integer" in why
    assert [(lo, hi) for lo, hi, _ in plan.uncovered] == sorted(g.uncovered_depths(ILLUM, plan.a, 400.0, 2000.0),
                                                                 reverse=True)
