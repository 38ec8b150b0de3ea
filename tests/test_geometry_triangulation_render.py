"""Triangulation against a rendered plane of known distance: the views' parallax gives the distance back."""

import pytest

from focus import focused
from lfproc import Camera
from lfproc import geometry as g

from lfproc import simulate  # noqa: E402
from lfproc.simulate import Noise, Plane, Scene  # noqa: E402
from lfproc.camera import MainLens
from plainref import measured_shift  # noqa: E402

CAMERA = focused(Camera(0.0014, 0.0182, 0.0364, MainLens(30.0, 30.0, f_number=2.0), micro_image_px=13), 600.0)


@pytest.mark.parametrize("distance_mm", [520.0, 760.0])
def test_views_parallax_triangulates_to_the_plane(distance_mm):
    z = distance_mm - CAMERA.main_optics.sensor_path_mm(CAMERA.mla_path_mm)
    footprint = CAMERA.mla_pitch_mm * abs(1 - z / CAMERA.main_optics.focal_length_mm)
    views, _, _ = simulate.render_ideal_views(CAMERA, Scene((Plane(distance_mm, Noise(3.0 * footprint, seed=5)),)),
                                              (24 * 13, 28 * 13), rim_radius_mm=None)
    c, gap = CAMERA.center_index, 4
    first, second = views[c, c - gap // 2, :, :, 0], views[c, c + gap // 2, :, :, 0]
    dx = measured_shift(first, second)
    expected = -g.refocus_parameter(CAMERA, distance_mm) * gap      # views G apart see slice a at -a*G lenses
    assert dx == pytest.approx(expected, abs=0.05)      # measured: within 0.012 px
    tri = g.triangulate(CAMERA, dx, gap)
    lo, hi = sorted(g.triangulate(CAMERA, [dx - 0.05, dx + 0.05], gap).distance_mm)
    assert lo <= distance_mm <= hi
    assert tri.distance_mm == pytest.approx(distance_mm, rel=0.005)
