"""LFM simulator (issue 21): renders of a light-field microscope whose rays obey the sine condition give
ground truth — each bead's sharpest slice holds its true z within the slice's depth of field, paraxial
(NA 0.5) and aplanatic (NA 1.2) alike, from ideal views and through calibration and decoding of a
rendered sensor image; at NA 1.2 the paraxial shifts miss (the render is not paraxial)."""

import numpy as np
import pytest

import lfproc
from lfproc import Camera, LightField, geometry
from lfproc.simulate import Bead, MicroscopeScene, Sheet, lens_of_point, render_microscope_sensor, \
    render_microscope_views

from conftest import SAMPLES

LENSES = (24, 24)
LFM_60X_FILE = SAMPLES / "cameras" / "lfm-60x-water.toml"


def microscope(magnification, na, n, pitch_mm, f_s_mm, m_hat):
    """A camera file with 6.5 µm pixels behind the relay that gives m̂ samples per lens."""
    relay = m_hat * 0.0065 / pitch_mm
    return Camera.from_toml_string(f"""name = "lfm-test"
[sensor]
pixel_pitch_mm = 0.0065
[mla]
pitch_mm = {pitch_mm}
focal_length_mm = {f_s_mm}
grid = "rectangular"
[microscope]
objective_magnification = {magnification}
numerical_aperture = {na}
immersion_index = {n}
tube_lens_focal_length_mm = 200.0
relay_magnification = {relay}
wavelength_nm = 520
""")


LFM_20X = microscope(20, 0.5, 1.33, 0.125, 2.433, 11)        # paraxial regime
LFM_60X = microscope(60, 1.2, 1.333, 0.1, 2.5, 15)            # aplanatic regime


def beads_at(camera, a_values):
    lat, zpa = camera.main_optics.lateral_sampling_um(camera), geometry.z_per_a_um(camera)
    corners = [(-5, -5), (5, -5), (-5, 5), (5, 5)]
    return tuple(Bead(x * lat, y * lat, a * zpa, radius_um=0.5 * lat) for (x, y), a in zip(corners, a_values))


def sharpest_bead_depths(camera, beads, views, a, **kwargs):
    """Per bead: (z of its sharpest slice, that slice's DOF), brightness peak over the 3 × 3 lenses around it."""
    stack = lfproc.refocus(LightField.from_views(views, camera), a, interpolation="cubic-spline", **kwargs)
    geo = geometry.microscope_slices(camera, a)
    found = []
    for bead in beads:
        r, q = (int(round(v)) for v in lens_of_point(camera, LENSES, bead.x_um, bead.y_um))
        i = int(np.argmax(stack[:, r - 1:r + 2, q - 1:q + 2, 0].max(axis=(1, 2))))
        found.append((float(geo.z_um[i]), float(geo.dof_um[i])))
    return found


A_SWEEP = np.round(np.arange(-0.7, 0.7001, 0.01), 6)


@pytest.mark.parametrize("camera, a_true", [(LFM_20X, (0.07, -0.12, 0.2, 0.5)),
                                            (LFM_60X, (0.07, -0.12, 0.2, 0.5))], ids=["NA0.5", "NA1.2"])
def test_each_bead_in_focus_at_its_depth(camera, a_true):
    beads = beads_at(camera, a_true)
    views, fraction = render_microscope_views(camera, MicroscopeScene(beads=beads), LENSES)
    inside = geometry.views_inside_aperture(camera)           # the views whose centre ray is inside the NA
    assert np.all(inside[fraction == 1.0]) and np.all(fraction[inside] > 0)
    for bead, (z, dof) in zip(beads, sharpest_bead_depths(camera, beads, views, A_SWEEP)):
        assert abs(z - bead.z_um) <= dof / 2, (bead.z_um, z, dof)


def test_high_na_render_is_not_paraxial():
    """Paraxial shifts a·(c − k) on the NA 1.2 render put beads more than half a DOF off: the render follows
    the sine condition, and geometry's aplanatic shifts are what hold the beads (test above)."""
    beads = beads_at(LFM_60X, (0.2, 0.5))
    views, _ = render_microscope_views(LFM_60X, MicroscopeScene(beads=beads), LENSES)
    c = LFM_60X.center_index
    k = (c - np.arange(LFM_60X.m_hat)).astype(float)
    paraxial = (np.repeat(k[:, None], LFM_60X.m_hat, 1), np.repeat(k[None, :], LFM_60X.m_hat, 0))
    misses = [abs(z - b.z_um) / dof for b, (z, dof) in
              zip(beads, sharpest_bead_depths(LFM_60X, beads, views, A_SWEEP, view_shifts=paraxial))]
    assert max(misses) > 0.5, misses


def test_textured_sheet_is_sharpest_at_its_depth():
    camera = LFM_20X
    lat, zpa = camera.main_optics.lateral_sampling_um(camera), geometry.z_per_a_um(camera)
    sheet = Sheet(z_um=0.15 * zpa, period_um=3.0 * lat, seed=4)
    views, _ = render_microscope_views(camera, MicroscopeScene(sheets=(sheet,)), LENSES)
    stack = lfproc.refocus(LightField.from_views(views, camera), A_SWEEP, interpolation="cubic-spline")
    inner = stack[:, 6:-6, 6:-6, 0]
    i = int(np.argmax(inner.reshape(len(A_SWEEP), -1).var(axis=1)))
    geo = geometry.microscope_slices(camera, A_SWEEP[i])
    assert abs(geo.z_um - sheet.z_um) <= geo.dof_um / 2, (geo.z_um, sheet.z_um, geo.dof_um)


def test_white_image_shows_the_na_disk():
    """Uniform emission: each micro image is a disk of radius f_s·tan θ' (sin θ' = NA/M) in pixels of the
    lenslets' focal plane; 1 inside (every ray passes), 0 outside."""
    camera = LFM_60X
    white = render_microscope_sensor(camera, None, (45, 45), pixel_samples=1, aperture_samples=1)
    sin_t = 1.2 / 60
    radius_px = camera.mla_focal_length_mm * sin_t / np.sqrt(1 - sin_t ** 2) / camera.lenslet_pixel_pitch_mm
    yy, xx = np.mgrid[-22:23, -22:23]
    r = np.hypot(yy, xx)                      # the central lens is centred on the sensor centre
    assert np.all(white[r < radius_px - 0.5] == 1.0)
    assert np.all(white[(r > radius_px + 0.5) & (r < 5)] == 0.0)


def test_rendered_capture_through_calibration_and_decoding(tmp_path):
    """The whole chain on a rendered 60x/1.2 sensor image: its white image calibrates, the capture decodes,
    and the aplanatic sweep finds every bead at its z within half the slice's DOF."""
    from lfproc.io import write_image
    from lfproc.api import prepare_decoding

    camera = Camera.from_toml(LFM_60X_FILE)
    beads = beads_at(camera, (0.07, -0.12, 0.2, 0.4))
    size = 371
    image = render_microscope_sensor(camera, MicroscopeScene(beads=beads), (size, size), pixel_samples=2,
                                     aperture_samples=2)
    white = render_microscope_sensor(camera, None, (size, size), pixel_samples=2, aperture_samples=1)
    write_image(str(tmp_path / "capture.tif"), np.round(60000 * image / image.max()).astype(np.uint16), {}, "tiff")
    write_image(str(tmp_path / "white.tif"), np.round(60000 * white).astype(np.uint16), {}, "tiff")
    lf = prepare_decoding(camera, white=str(tmp_path / "white.tif"), cache=True).decode(str(tmp_path / "capture.tif"))
    stack = lfproc.refocus(lf, A_SWEEP, interpolation="cubic-spline")
    geo = geometry.microscope_slices(camera, A_SWEEP)
    rows, cols = np.mgrid[:lf.lens_shape[0], :lf.lens_shape[1]]
    centres = lf.grid.lens_xy(rows, cols)                                  # (Ny, Nx, 2) sensor px
    pixel_um = camera.lenslet_pixel_pitch_mm * 1000
    for bead in beads:
        # the bead's image on the sensor: −M·(x, y) from the axis (the sensor centre), in lenslet-plane pixels
        xy = (size - 1) / 2 - camera.main_optics.objective_magnification * np.array([bead.x_um, bead.y_um]) / pixel_um
        r, q = np.unravel_index(np.argmin(np.hypot(*(centres - xy).transpose(2, 0, 1))), lf.lens_shape)
        i = int(np.argmax(stack[:, r - 1:r + 2, q - 1:q + 2, 0].max(axis=(1, 2))))
        assert abs(geo.z_um[i] - bead.z_um) <= geo.dof_um[i] / 2, (bead.z_um, geo.z_um[i], geo.dof_um[i])


@pytest.mark.parametrize("make, words", [(lambda: Bead(0, 0, float("nan")), "z_um"),
                                         (lambda: Bead(0, 0, 1, radius_um=0), "radius_um"),
                                         (lambda: Sheet(1.0, period_um=-2), "period_um"),
                                         (lambda: Sheet(1.0, waves=0), "waves")])
def test_bad_beads_and_sheets_are_one_line_errors(make, words):
    from lfproc import LfprocError

    with pytest.raises(LfprocError, match=words):
        make()


def test_microscope_render_needs_a_microscope_camera():
    from lfproc import LfprocError

    camera = Camera.from_toml(SAMPLES / "sample" / "camera.toml")
    with pytest.raises(LfprocError, match=r"\[microscope\]"):
        render_microscope_views(camera, MicroscopeScene(), (4, 4))
