"""Camera.main_optics: the one field that holds everything in front of the micro lens array (issues 31, 37).

A plain frozen dataclass: the main optics are one explicit field (``main_optics=MainLens(...)`` or a
``Microscope``), read as ``camera.main_optics``; a copy with other optics is ``camera.with_optics(...)``.
Cameras compare equal by value, survive pickling (batch workers) and ``dataclasses.replace``.
"""

from __future__ import annotations

import dataclasses
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
    return lfproc.Camera(0.01, 0.25, 2.749, MainLens(99.5145, 109.5145, principal_plane_gap_mm=-33.184, f_number=4.0),
                         mla_principal_plane_gap_mm=0.374, **extra)


def test_a_camera_is_a_plain_dataclass_with_one_field_for_its_main_optics():
    one = lfproc.Camera(pixel_pitch_mm=0.01, mla_pitch_mm=0.25, mla_focal_length_mm=2.749,
                        main_optics=MainLens(99.5145, 109.5145, -33.184, 4.0), mla_principal_plane_gap_mm=0.374)
    flat = _flat()
    assert one == flat and hash(one) == hash(flat)
    assert [f.name for f in dataclasses.fields(flat)][:4] == ["pixel_pitch_mm", "mla_pitch_mm", "mla_focal_length_mm",
                                                              "main_optics"]
    assert isinstance(flat.main_optics, MainLens) and isinstance(flat.main_optics, MainOptics)
    lens = flat.main_optics
    assert (lens.focal_length_mm, lens.image_distance_mm, lens.principal_plane_gap_mm, lens.f_number) == \
        (99.5145, 109.5145, -33.184, 4.0)
    assert lens.object_space is SENSOR_MM and math.isinf(lens.exit_pupil_distance_mm)
    # no values of the lens pass through the camera: they are the optics' own
    for name in ("main_focal_length_mm", "image_distance_mm", "f_number", "exit_pupil_distance_mm", "main_lens",
                 "microscope", "object_space", "require_main_lens", "sensor_to_main_lens_mm"):
        assert not hasattr(flat, name), name


def test_the_paper_camera_file_reads_into_a_main_lens_and_writes_back_the_same_file():
    camera = lfproc.Camera.from_toml(CAMERAS / "paper-f100.toml")
    assert isinstance(camera.main_optics, MainLens)
    again = lfproc.Camera.from_toml_string(camera.to_toml(), "again")
    assert again == camera and again.to_toml() == camera.to_toml()


def test_with_optics_changes_the_main_lens_value_it_names_and_keeps_the_rest():
    camera = _flat(micro_image_px=25)
    moved = camera.with_optics(replace(camera.main_optics, image_distance_mm=119.5145))
    assert moved.main_optics.image_distance_mm == 119.5145
    assert moved.main_optics.focal_length_mm == camera.main_optics.focal_length_mm
    assert moved.main_optics.f_number == 4.0 and moved.mla_focal_length_mm == camera.mla_focal_length_mm
    assert moved.m_hat == camera.m_hat and moved == replace(camera, main_optics=moved.main_optics)
    # the geometry follows the new b_U: the slice at a = 0 of a lens focused 10 mm beyond f_U is finite
    assert math.isfinite(geometry.slice_geometry(moved, 0.0).distance_mm)
    assert camera.with_optics(replace(camera.main_optics, f_number=None)).main_optics.f_number is None
    with pytest.raises(lfproc.LfprocError, match="main_lens.image_distance_mm = 90.0 is below"):
        camera.with_optics(replace(camera.main_optics, image_distance_mm=90.0))   # validated like a file


def test_a_microscope_is_the_other_kind_of_main_optics():
    scope = Microscope(objective_magnification=20.0, numerical_aperture=0.5, immersion_index=1.33,
                       tube_lens_focal_length_mm=180.0)
    camera = lfproc.Camera(0.0065, 0.125, 2.433, scope)
    assert camera.main_optics is scope and isinstance(scope, MainOptics)
    assert camera.main_optics.object_space is NATIVE_PLANE_UM
    assert lfproc.Camera(0.0065, 0.125, 2.433, scope) == camera
    assert camera != lfproc.Camera(0.0065, 0.125, 2.433, MainLens(50.0, 50.0))
    with pytest.raises(lfproc.LfprocError, match="numerical_aperture"):
        camera.with_optics(replace(scope, numerical_aperture=1.5))


def test_a_camera_without_main_optics_is_refused_in_one_line():
    with pytest.raises(lfproc.LfprocError, match=r"needs main optics \(a \[main_lens\] or \[microscope\]") as err:
        lfproc.Camera(pixel_pitch_mm=0.01, mla_pitch_mm=0.25, mla_focal_length_mm=2.749, main_optics=None)
    assert "\n" not in str(err.value)
    with pytest.raises(lfproc.LfprocError, match="needs main optics"):
        lfproc.Camera(0.01, 0.25, 2.749, 100.0)          # a focal length is not optics


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
        assert geo.space is camera.main_optics.object_space and geo.space.keys == names
        for field, name in zip((geo.depth, geo.near, geo.far, geo.dof), names):
            assert getattr(geo, name) is field
        assert all(getattr(geo, name) is None for name in other)
        assert list(geo.records()[0]) == ["a", *names]
        # near is the limit nearer the optics: the smaller distance from the sensor, the larger z
        nearer = np.all(geo.near <= geo.depth) if camera is lens else np.all(geo.near >= geo.depth)
        assert nearer and np.allclose(geo.dof, np.abs(geo.far - geo.near))
