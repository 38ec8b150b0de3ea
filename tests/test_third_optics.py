"""Acceptance of issue 37: a third kind of main optics, written only here, goes through the whole API and
``lfproc.geometry`` with no module of lfproc knowing it.

The optics: a photographic lens whose distances are read as on its focus scale, in *metres from its front
principal plane* (not mm from the sensor): the object space of a lens user, not of the paper. It is not a
``MainLens`` (nor a subclass): it implements the ``MainOptics`` interface itself, with its own object space
(``distance_m``, ``near_m``, ``far_m``, ``dof_m``). It is chosen because every place that used to assume
"distances are mm from the sensor, so the optics are a main lens" (keys, units, origin, which limit is nearer,
infinity, labels, file names, planning, refusals) has to take its words from the optics to get it right.

Its tags are checked against the thin-lens closed form of that lens, written out here (Gaussian imaging
between the principal planes, 1/f = 1/s + 1/s'; the paper's ray pairs meet w = A·p_m/δ behind the MLA,
A = a for a slice and A = (2ac ± 1)/(2c ∓ 1) for its DOF limits, Eqs. 13–31; the virtual cameras of Eq. 17 at
F_i = −i·δ·f), not against lfproc's numbers.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import pytest

import lfproc
from conftest import SAMPLES
from lfproc import geometry
from lfproc.camera import Camera, MainLens, MainOptics, ObjectSpace, RayTransfer, UsableRange, ViewPlacement, ViewPupil

#: metres from the lens's front principal plane, shrinking towards the lens
FOCUS_SCALE_M = ObjectSpace("m", "m", "from the lens's front principal plane", ("distance_m", "near_m", "far_m", "dof_m"),
                            0.001, -1.0, "d", "", ".4f")


@dataclass(frozen=True)
class FocusScaleLens:
    """A thin lens (f, b behind it to the MLA, f-number N) that reports distances as its focus scale does:
    metres from its front principal plane. Image-side telecentric (its stop in its front focal plane)."""

    focal_length_mm: float
    image_distance_mm: float
    f_number: float

    object_space = FOCUS_SCALE_M
    exit_pupil_distance_mm = math.inf
    relay_magnification = 1.0
    wave_optics = None

    @property
    def image_aperture_sine(self) -> float:
        return 1.0 / (2.0 * self.f_number)

    def validate(self, where: str) -> None:
        if not 0 < self.focal_length_mm <= self.image_distance_mm:
            raise lfproc.LfprocError(f"{where}: the focus scale lens needs 0 < f <= b")

    def transfer(self) -> RayTransfer:
        f, b = self.focal_length_mm, self.image_distance_mm
        return RayTransfer(1.0, b, -1.0 / f, 1.0 - b / f)        # T(b)·L(f) from the principal plane

    def object_position(self, shift, pitch_mm, slope_gap, mla_path_mm):
        """Newton: the image point w = g/N behind the MLA, x' = b + w − f behind F', x = f²/x' in front of F."""
        f = self.focal_length_mm
        with np.errstate(divide="ignore", invalid="ignore"):
            x_image = np.asarray(shift, dtype=np.float64) * pitch_mm / slope_gap + (self.image_distance_mm - f)
            metres = (f + f * f / x_image) / 1000.0
        return np.where(x_image > 0, metres, np.inf)

    def refocus_parameter(self, camera, position):
        metres = np.asarray(position, dtype=np.float64)
        if np.any(~(metres * 1000.0 > self.focal_length_mm)):
            raise lfproc.LfprocError(f"{position} m is not beyond the lens's front focal plane")
        f = self.focal_length_mm
        x_image = np.where(np.isinf(metres), 0.0, f * f / (metres * 1000.0 - f))
        delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
        return (x_image - (self.image_distance_mm - f)) * delta / camera.mla_pitch_mm

    def usable_range(self, camera) -> UsableRange:
        delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
        low = -(self.image_distance_mm - self.focal_length_mm) * delta / camera.mla_pitch_mm
        return UsableRange(low, math.inf, math.inf, self.focal_length_mm / 1000.0, "the lens's front focal plane")

    def refusal(self, camera, a: float) -> str:
        return "focuses beyond infinity" if a < self.usable_range(camera).low else "focuses inside the front focal length"

    def lit_view_extent(self, sample_pitch_mm, mla_focal_length_mm, center_index) -> float:
        return float(center_index)

    def wave_depth_of_field(self) -> float:
        return 0.0

    def place_views(self, camera, offsets) -> ViewPlacement:
        delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
        i = np.asarray(offsets, dtype=np.float64)
        slopes = -i * delta + 0.0
        eps = self.image_distance_mm - self.focal_length_mm
        return ViewPlacement(i, slopes * self.focal_length_mm, np.degrees(np.arctan(slopes * eps / self.focal_length_mm))
                             + 0.0, delta * self.focal_length_mm)

    def inside_aperture(self, camera) -> np.ndarray:
        c = camera.center_index
        pos = self.place_views(camera, np.arange(-c, c + 1)).position_mm
        radius = self.focal_length_mm / (2.0 * self.f_number)
        return pos[:, None] ** 2 + pos[None, :] ** 2 <= radius * radius * (1.0 + 1e-12)

    def view_pupil(self, camera) -> ViewPupil:
        c = camera.center_index
        views = self.place_views(camera, np.arange(-c, c + 1))
        return ViewPupil(views.position_mm, views.baseline_mm, self.focal_length_mm, self.f_number)

    def lateral_sampling_um(self, camera):
        return None

    def summary(self, camera) -> dict:
        return {"focal_length_mm": self.focal_length_mm, "image_distance_mm": self.image_distance_mm}

    def describe(self) -> str:
        return f"focus-scale lens, f {self.focal_length_mm:g} mm"

    def toml_lines(self) -> list:
        return ["[focus_scale_lens]", f"focal_length_mm = {self.focal_length_mm!r}",
                f"image_distance_mm = {self.image_distance_mm!r}", f"f_number = {self.f_number!r}"]


# ----------------------------------------------------------------------------------------- the closed forms
def _metres(camera, big_a):
    """Thin lens: the pair A lenses apart (slopes one view step apart) meets w = A·p_m/δ behind the MLA; its
    object is s = f·(b + w)/(b + w − f) in front of the front principal plane, in metres (inf if virtual)."""
    lens = camera.main_optics
    f, b = lens.focal_length_mm, lens.image_distance_mm
    w = np.asarray(big_a, dtype=np.float64) * camera.mla_pitch_mm * camera.mla_focal_length_mm / camera.sample_pitch_mm
    with np.errstate(divide="ignore"):
        s = f * (b + w) / (b + w - f)
    return np.where(b + w - f > 0, s / 1000.0, np.inf)


def _closed_form(camera, a, extent=None):
    """(position, near, far) in metres of slices a: the paper's bounding pairs A = (2ac ± 1)/(2c ∓ 1) in front
    of the focus distance (every a ≥ 1/(2c), Eqs. 23–31), c the extent of the views summed (the full micro
    image where ``extent`` is None)."""
    c = camera.center_index if extent is None else extent
    a = np.asarray(a, dtype=np.float64)
    near, far = _metres(camera, (2 * a * c + 1) / (2 * c - 1)), _metres(camera, (2 * a * c - 1) / (2 * c + 1))
    return _metres(camera, a), near, far


SAMPLE = Camera.from_toml(SAMPLES / "sample" / "camera.toml")


def _focus_scale_camera(b_mm=50.0):
    lens = SAMPLE.main_optics
    return SAMPLE.with_optics(FocusScaleLens(lens.focal_length_mm, b_mm, lens.f_number))


def test_the_third_optics_is_its_own_kind_and_implements_the_interface():
    camera = _focus_scale_camera()
    assert isinstance(camera.main_optics, MainOptics)
    assert not isinstance(camera.main_optics, MainLens) and not issubclass(FocusScaleLens, MainLens)


def test_slices_views_and_planning_of_lfproc_geometry_follow_the_closed_form():
    camera = _focus_scale_camera(51.0)
    a = np.array([0.5, 1.0, 2.0, 4.0])
    geo = geometry.slice_geometry(camera, a)
    position, near, far = _closed_form(camera, a)
    assert geo.space is FOCUS_SCALE_M and [*geo.records()[0]] == ["a", "distance_m", "near_m", "far_m", "dof_m"]
    assert geo.distance_mm is None and geo.z_um is None                 # the contract's names: another space
    np.testing.assert_allclose(geo.depth, position, rtol=1e-12)
    np.testing.assert_allclose(geo.near, near, rtol=1e-12)
    np.testing.assert_allclose(geo.far, far, rtol=1e-12)
    assert np.all(geo.near < geo.depth) and np.all(geo.depth < geo.far)   # nearer the lens: fewer metres
    # the slice at infinity: b + w = f, and the inverse of a position
    a_inf = -(51.0 - 50.0) * camera.sample_pitch_mm / camera.mla_focal_length_mm / camera.mla_pitch_mm
    assert geometry.infinity_parameter(camera) == pytest.approx(a_inf, rel=1e-12)
    assert float(geometry.position_parameter(camera, float(position[1]))) == pytest.approx(1.0, rel=1e-9)
    # views: Eq. 17's virtual cameras, F_i = −i·δ·f, neighbours δ·f apart
    views = geometry.view_geometry(camera)
    delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
    np.testing.assert_allclose(views.position_mm, -np.arange(-5, 6) * delta * 50.0, rtol=1e-12, atol=1e-15)
    assert views.baseline_mm == pytest.approx(delta * 50.0, rel=1e-12) and views.records()[0].keys() == {
        "i", "position_mm", "tilt_deg"}
    # planning in metres: the fewest slices whose DOFs cover 0.4 m to 2 m
    planned = geometry.plan_slices(camera, 0.4, 2.0)
    covered = geometry.slice_geometry(camera, planned)
    assert covered.far[0] >= 2.0 and covered.near[-1] <= 0.4 and np.all(covered.far[1:] >= covered.near[:-1])
    assert not geometry.uncovered_depths(camera, planned, 0.4, 2.0)
    # the usable range in the optics' own words and units
    with pytest.raises(lfproc.LfprocError, match=r"focuses beyond infinity; usable: a from .* \(infinity\) to \+inf "
                                                 r"\(approaching the lens's front focal plane at 0.0500 m\)"):
        geometry.check_usable_a(camera, [a_inf - 1.0])
    assert geometry.usable_range_text(camera, None, 3.0, "distance_m").startswith("distance_m from ")
    with pytest.raises(lfproc.LfprocError, match="in mm from the sensor; this camera's optics"):
        geometry.slice_distance_mm(camera, 1.0)                        # a function of mm from the sensor


@pytest.fixture(scope="module")
def third(tmp_path_factory):
    """The sample capture decoded with the focus-scale lens's camera (the same lens the sample was rendered
    with, its distances read in metres from its front principal plane): calibrate, read, then the products."""
    camera = _focus_scale_camera()
    white, capture = SAMPLES / "sample" / "white.png", SAMPLES / "sample" / "capture.png"
    grid = lfproc.calibrate_white(str(white), camera)
    lf = lfproc.read_light_field(str(capture), camera, white=str(white), grid=grid)
    return camera, lf


def test_calibrate_read_focal_stack_views_depth_and_save(third, tmp_path):
    camera, lf = third
    assert lf.camera.main_optics is camera.main_optics
    a = [0.5, 1.0, 2.0]
    with pytest.warns(lfproc.LfprocWarning):            # the outer views shift off the sample's border band
        fs = lfproc.focal_stack(lf, a=a)
    position, near, far = _closed_form(camera, a, geometry.summed_view_extent(lf.view_mask))   # the views with light
    np.testing.assert_allclose(fs.depth, position, rtol=1e-12)
    np.testing.assert_allclose(fs.near, near, rtol=1e-12)
    np.testing.assert_allclose(fs.far, far, rtol=1e-12)
    assert fs.distance_mm is None and fs.z_um is None and fs.space is FOCUS_SCALE_M
    assert " m from the lens's front principal plane" in repr(fs)
    r, delta = geometry.summed_view_extent(lf.view_mask), camera.sample_pitch_mm / camera.mla_focal_length_mm
    assert fs.aperture_f_number == pytest.approx(math.sqrt(3.0) / (2.0 * (2.0 * r + 1.0) * delta), rel=1e-12)
    written = fs.save(tmp_path / "slices", stem="s")
    sidecar = json.loads(open(written[1].rsplit(".", 1)[0] + ".json").read())
    assert sidecar["distance_m"] == pytest.approx(float(position[1]), rel=1e-12) and "distance_mm" not in sidecar
    assert [p.split("_")[-1] for p in written] == ["a+0.500.tif", "a+1.000.tif", "a+2.000.tif"]   # named by a
    with pytest.raises(lfproc.LfprocError, match=r"distance_mm= names positions .* in m from the lens.s front principal plane; give a=$"):
        lfproc.focal_stack(lf, distance_mm=[500.0])
    with pytest.raises(lfproc.LfprocError, match=r"capture.png: a=-9 focuses beyond infinity; usable: a from \+0 "
                                                 r"\(infinity\) to \+[\d.]+ \(0\.\d+ m\)$"):   # the capture's one range, in m
        lfproc.focal_stack(lf, a=[-9.0])
    # the views: Eq. 17's virtual cameras, tagged as the commands tag them
    vs = lfproc.view_stack(lf)
    delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
    centre = np.zeros(2) if lf.view_centre is None else np.asarray(lf.view_centre)
    np.testing.assert_allclose(vs.position_mm, (vs.view - camera.center_index + centre) * -delta * 50.0,
                               rtol=1e-9, atol=1e-12)
    assert vs.save(tmp_path / "views", stem="s")
    # the depth map in metres: each known lens's depth is the thin lens at its sharpest slice
    dm = lfproc.depth_map(lf)
    known = np.isfinite(dm.a) & (dm.a > geometry.infinity_parameter(camera))
    assert known.mean() > 0.5 and dm.space is FOCUS_SCALE_M and dm.distance_mm is None
    np.testing.assert_allclose(dm.depth[known], _metres(camera, dm.a[known].astype(np.float64)), rtol=1e-5)
    paths = dm.save(tmp_path / "depth", stem="s")
    assert set(paths) == {"depth", "confidence", "allfocus", "preview"}   # no point cloud: no main lens's chief rays
    tags = json.loads(open(paths["depth"].rsplit(".", 1)[0] + ".json").read())
    assert tags["unit"] == "m" and "distance_m of the sharpest slice" in tags["content"]
