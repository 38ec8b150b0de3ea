"""The [microscope] camera file (ARCHITECTURE.md "Microscope camera file"): parsing, validation, derived values."""

import math
from pathlib import Path

import pytest

from lfproc import LfprocError
from lfproc.camera import Camera, Microscope
from scopefile import microscope_toml

SAMPLES = Path(__file__).resolve().parents[1] / "lfproc" / "samples" / "cameras"

CONTRACT = microscope_toml(relay=1.4286, wavelength=510)     # the contract's example, line for line


def _cam(text):
    return Camera.from_toml_string(text, source="scope.toml")


def test_contract_example_parses_with_the_relay():
    cam = _cam(CONTRACT)
    assert isinstance(cam.main_optics, Microscope) and cam.telecentric
    scope = cam.main_optics
    assert (scope.objective_magnification, scope.numerical_aperture, scope.immersion_index) == (20.0, 0.5, 1.33)
    # the pixel at the lenslet focal plane is 6.5 um / 1.4286 = 4.55 um: 125 / 4.55 = 27.47 px per lens
    assert cam.lenslet_pixel_pitch_mm == pytest.approx(0.0065 / 1.4286, rel=1e-15)
    assert cam.pitch_px == pytest.approx(0.125 * 1.4286 / 0.0065, rel=1e-12)
    assert cam.m_hat == 27                       # the largest odd integer not above 27.47
    assert cam.effective_pixel_pitch_mm == pytest.approx(0.125 / 27, rel=1e-15)
    assert scope.objective_focal_length_mm == pytest.approx(9.0)
    assert scope.axial_magnification == pytest.approx(400 / 1.33)
    assert scope.wavelength_mm == pytest.approx(510e-6)


def test_sample_cameras_parse_and_round_trip():
    for name in ("lfm-20x.toml", "lfm-60x-water.toml"):
        cam = Camera.from_toml(SAMPLES / name)
        assert isinstance(cam.main_optics, Microscope)
        again = Camera.from_toml_string(cam.to_toml())
        assert again == cam and again.main_optics == cam.main_optics
    assert Camera.from_toml(SAMPLES / "lfm-20x.toml") == _cam(CONTRACT)


def test_relay_defaults_to_one_and_wavelength_to_none():
    text = CONTRACT.replace("relay_magnification = 1.4286\n", "").replace("wavelength_nm = 510\n", "")
    cam = _cam(text)
    assert cam.main_optics.relay_magnification == 1.0 and cam.main_optics.wavelength_nm is None
    assert cam.m_hat == 19                       # 125 / 6.5 = 19.23
    assert cam.main_optics.wavelength_mm == pytest.approx(550e-6)


@pytest.mark.parametrize("edit, mention", [
    (("numerical_aperture = 0.5", "numerical_aperture = 1.4"), "numerical_aperture"),
    (("numerical_aperture = 0.5", "numerical_aperture = 1.33"), "immersion_index"),
    (("numerical_aperture = 0.5", "numerical_aperture = -0.5"), "microscope.numerical_aperture"),
    (("objective_magnification = 20.0", "objective_magnification = 0"), "microscope.objective_magnification"),
    (("immersion_index = 1.33", "immersion_index = 0.9"), "microscope.immersion_index"),
    (("tube_lens_focal_length_mm = 180.0", "tube_lens_focal_length_mm = -180.0"), "tube_lens_focal_length_mm"),
    (("relay_magnification = 1.4286", "relay_magnification = 0"), "microscope.relay_magnification"),
    (("wavelength_nm = 510", "wavelength_nm = -1"), "microscope.wavelength_nm"),
    (("wavelength_nm = 510", "wavelength_nm = \"green\""), "microscope.wavelength_nm"),
    (("wavelength_nm = 510", "wavelength_nm = nan"), "microscope.wavelength_nm"),
    (("numerical_aperture = 0.5\n", ""), "missing microscope.numerical_aperture"),
    (("objective_magnification = 20.0\n", ""), "missing microscope.objective_magnification"),
    (("immersion_index = 1.33\n", ""), "missing microscope.immersion_index"),
    (("tube_lens_focal_length_mm = 180.0\n", ""), "missing microscope.tube_lens_focal_length_mm"),
    (("wavelength_nm = 510", "wavelenght_nm = 510"), "unknown key 'wavelenght_nm' in [microscope]"),
    (("wavelength_nm = 510", "wavelength_nm = 510\naplanatic = \"yes\""), "microscope.aplanatic"),
])
def test_bad_microscope_values_are_one_line_errors(edit, mention):
    with pytest.raises(LfprocError) as info:
        _cam(CONTRACT.replace(*edit))
    message = str(info.value)
    assert "\n" not in message and message.startswith("scope.toml:") and mention in message, message


def test_both_tables_or_neither_is_refused():
    both = CONTRACT + "[main_lens]\nfocal_length_mm = 100.0\nimage_distance_mm = 100.0\n"
    with pytest.raises(LfprocError, match=r"both \[main_lens\] and \[microscope\]"):
        _cam(both)
    neither = CONTRACT.split("[microscope]")[0]
    with pytest.raises(LfprocError, match=r"missing table \[main_lens\] \(or \[microscope\]"):
        _cam(neither)


def test_microscope_that_is_not_a_table_is_refused():
    text = 'microscope = 3\n' + CONTRACT.split("[microscope]")[0]
    with pytest.raises(LfprocError, match=r"'microscope' must be a table \[microscope\]"):
        _cam(text)


def test_a_camera_has_one_main_optics():
    cam = _cam(CONTRACT)
    assert isinstance(cam.main_optics, Microscope)
    with pytest.raises(LfprocError, match="needs main optics"):
        Camera(cam.pixel_pitch_mm, cam.mla_pitch_mm, cam.mla_focal_length_mm, None)


def test_main_lens_quantities_refuse_on_a_microscope():
    from lfproc import geometry
    cam = _cam(CONTRACT)
    with pytest.raises(LfprocError, match=r"needs a main lens \(\[main_lens\]\).*objective"):
        geometry.virtual_camera_plane_mm(cam)
    with pytest.raises(LfprocError, match="in mm from the sensor; this camera's optics"):
        geometry.slice_distance_mm(cam, 1.0)


def test_aplanatic_switch_parses():
    on = _cam(CONTRACT + "aplanatic = true\n")
    off = _cam(CONTRACT + "aplanatic = false\n")
    assert on.main_optics.aplanatic is True and off.main_optics.aplanatic is False
    assert _cam(CONTRACT).main_optics.aplanatic is None
    assert Camera.from_toml_string(on.to_toml()).main_optics.aplanatic is True
    assert math.isinf(on.main_optics.exit_pupil_distance_mm)
