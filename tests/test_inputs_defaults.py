"""Issue 30, measured defaults: m̂ is the largest odd integer at most the *measured* micro image pitch when the
camera file states none (the issue's case: nominal 46.5 px gives 45, the white image measures 48.2 px: 47)."""

from lfproc.camera import Camera
from lfproc.camera import MainLens
from lfproc.inputs import measured_m_hat

NOMINAL = dict(pixel_pitch_mm=0.0014, mla_pitch_mm=0.0014 * 46.5, mla_focal_length_mm=0.025,
               main_optics=MainLens(6.45, 6.5, f_number=2.0), grid="hexagonal")


def test_m_hat_follows_the_measured_pitch_unless_the_camera_file_states_it():
    camera = Camera(**NOMINAL)
    assert camera.m_hat == 45 and not camera.micro_image_px_given
    used = measured_m_hat(camera, 48.2, "GRID.json")
    assert used.camera.m_hat == 47 and used.camera.micro_image_px_given
    assert "48.200 px measured by GRID.json" in used.note and "gives 45" in used.note and "\n" not in used.note
    assert used.camera.pitch_px == camera.pitch_px                  # only m̂ changes
    assert measured_m_hat(camera, 46.9, "GRID.json").note is None   # the same m̂: nothing to say
    assert measured_m_hat(camera, 46.9, "GRID.json").camera is camera
    stated = Camera(**NOMINAL, micro_image_px=45)
    assert stated.micro_image_px_given and measured_m_hat(stated, 48.2).camera.m_hat == 45
    assert Camera.from_toml_string(stated.to_toml()).micro_image_px_given    # written files state theirs
