"""Camera.main_optics: the one field that holds everything in front of the micro lens array (issue 31).

The main lens can be given as one object (``main_optics=MainLens(...)``) or by its camera-file values
(``main_focal_length_mm=...``); both build the same camera. A microscope is the other kind of main optics;
mixing the two is refused. Cameras survive pickling (batch workers) and ``dataclasses.replace``.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import lfproc
from lfproc import geometry
from lfproc.camera import NATIVE_PLANE_UM, SENSOR_MM, MainLens, MainOptics, Microscope

CAMERAS = Path(lfproc.__file__).parent / "samples" / "cameras"


def _flat(**extra):
    return lfproc.Camera(pixel_pitch_mm=0.01, mla_pitch_mm=0.25, mla_focal_length_mm=2.749,
                         mla_principal_plane_gap_mm=0.374, main_focal_length_mm=99.5145,
                         main_principal_plane_gap_mm=-33.184, image_distance_mm=109.5145, f_number=4.0, **extra)


def test_a_main_lens_given_as_one_object_is_the_camera_given_by_its_file_values():
    one = lfproc.Camera(pixel_pitch_mm=0.01, mla_pitch_mm=0.25, mla_focal_length_mm=2.749,
                        mla_principal_plane_gap_mm=0.374,
                        main_optics=MainLens(99.5145, 109.5145, principal_plane_gap_mm=-33.184, f_number=4.0))
    flat = _flat()
    assert one == flat and hash(one) == hash(flat)
    assert isinstance(flat.main_optics, MainLens) and isinstance(flat.main_optics, MainOptics)
    assert (flat.main_focal_length_mm, flat.image_distance_mm, flat.main_principal_plane_gap_mm, flat.f_number) == \
        (99.5145, 109.5145, -33.184, 4.0)
    assert flat.microscope is None and flat.object_space is SENSOR_MM
    assert math.isinf(flat.exit_pupil_distance_mm)


def test_the_paper_camera_file_reads_into_a_main_lens_and_writes_back_the_same_file():
    camera = lfproc.Camera.from_toml(CAMERAS / "paper-f100.toml")
    assert isinstance(camera.main_optics, MainLens)
    again = lfproc.Camera.from_toml_string(camera.to_toml(), "again")
    assert again == camera and again.to_toml() == camera.to_toml()


def test_replace_changes_the_main_lens_value_it_names_and_keeps_the_rest():
    camera = _flat()
    moved = replace(camera, image_distance_mm=119.5145)
    assert moved.image_distance_mm == 119.5145 and moved.main_focal_length_mm == camera.main_focal_length_mm
    assert moved.f_number == 4.0 and moved.mla_focal_length_mm == camera.mla_focal_length_mm
    # the geometry follows the new b_U: the slice at a = 0 of a lens focused 10 mm beyond f_U is finite
    assert math.isfinite(geometry.slice_geometry(moved, 0.0).distance_mm)
    assert replace(camera, f_number=None).f_number is None


def test_a_microscope_is_the_other_kind_of_main_optics():
    scope = Microscope(objective_magnification=20.0, numerical_aperture=0.5, immersion_index=1.33,
                       tube_lens_focal_length_mm=180.0)
    camera = lfproc.Camera(pixel_pitch_mm=0.0065, mla_pitch_mm=0.125, mla_focal_length_mm=2.433, microscope=scope)
    assert camera.main_optics is scope and camera.microscope is scope and isinstance(scope, MainOptics)
    assert camera.object_space is NATIVE_PLANE_UM
    assert camera.main_focal_length_mm is None and camera.f_number is None and camera.image_distance_mm is None
    same = lfproc.Camera(pixel_pitch_mm=0.0065, mla_pitch_mm=0.125, mla_focal_length_mm=2.433, main_optics=scope)
    assert same == camera
    with pytest.raises(lfproc.LfprocError, match="no main lens"):
        lfproc.Camera(pixel_pitch_mm=0.0065, mla_pitch_mm=0.125, mla_focal_length_mm=2.433, microscope=scope,
                      main_focal_length_mm=50.0)
    with pytest.raises(lfproc.LfprocError, match="no main lens"):
        replace(camera, f_number=4.0)
    with pytest.raises(lfproc.LfprocError, match="not both"):
        lfproc.Camera(pixel_pitch_mm=0.0065, mla_pitch_mm=0.125, mla_focal_length_mm=2.433, microscope=scope,
                      main_optics=MainLens(50.0, 50.0))


def test_a_camera_without_main_optics_is_refused_in_one_line():
    with pytest.raises(lfproc.LfprocError, match=r"needs a main lens .* or a \[microscope\] table") as err:
        lfproc.Camera(pixel_pitch_mm=0.01, mla_pitch_mm=0.25, mla_focal_length_mm=2.749, main_focal_length_mm=100.0)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("name", ["paper-f100.toml", "double-gauss-f100.toml", "lfm-20x.toml"])
def test_cameras_survive_pickling_with_their_optics_and_their_given_m_hat(name):
    camera = lfproc.Camera.from_toml(CAMERAS / name)
    back = pickle.loads(pickle.dumps(camera))
    assert back == camera and back.main_optics == camera.main_optics
    assert back.micro_image_px_given == camera.micro_image_px_given
    a = np.linspace(-1.0, 2.0, 7)
    for one, two in zip(geometry.slice_geometry(camera, a).records(), geometry.slice_geometry(back, a).records()):
        assert one == two


def test_slice_geometry_reports_one_set_of_fields_in_the_optics_space():
    lens = lfproc.Camera.from_toml(CAMERAS / "paper-f100.toml")
    scope = lfproc.Camera.from_toml(CAMERAS / "lfm-20x.toml")
    for camera, names, other in ((lens, ("distance_mm", "near_mm", "far_mm", "dof_mm"),
                                  ("z_um", "z_near_um", "z_far_um", "dof_um")),
                                 (scope, ("z_um", "z_near_um", "z_far_um", "dof_um"),
                                  ("distance_mm", "near_mm", "far_mm", "dof_mm"))):
        geo = geometry.slice_geometry(camera, np.array([0.5, 1.0, 2.0]))
        assert geo.space is camera.object_space and geo.space.keys == names
        for field, name in zip((geo.depth, geo.near, geo.far, geo.dof), names):
            assert getattr(geo, name) is field
        assert all(getattr(geo, name) is None for name in other)
        assert list(geo.records()[0]) == ["a", *names]
        # near is the limit nearer the optics: the smaller distance from the sensor, the larger z
        nearer = np.all(geo.near <= geo.depth) if geo.space.from_sensor else np.all(geo.near >= geo.depth)
        assert nearer and np.allclose(geo.dof, np.abs(geo.far - geo.near))
