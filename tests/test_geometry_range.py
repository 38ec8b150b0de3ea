"""Only real slices (issue 30): the usable range of a runs from the slice at infinity to the front focal plane.

Reference: the slice distance itself (Eq. 21, `slice_distance_mm`) on a dense sweep of a — a slice is real
where that distance is finite and beyond the main lens's front focal plane L + f_U — against the closed-form
bounds of `usable_a_range`; and the refusals' wording (the whole range, low to high, in a and in distance).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from conftest import SAMPLES, assert_clean_error, run_cli
from lfproc import Camera, LfprocError, geometry


def _camera(name: str) -> Camera:
    return Camera.from_toml(SAMPLES / "cameras" / f"{name}.toml")


CAMERAS = {"sample (at infinity)": lambda: Camera.from_toml(SAMPLES / "sample" / "camera.toml"),
           "paper f100, b_U = f_U + 10 mm": lambda: _camera("paper-f100-b10"),
           "illum-like (finite exit pupil)": lambda: _camera("illum-like")}


@pytest.mark.parametrize("name", list(CAMERAS))
def test_the_usable_range_is_where_slices_focus_in_front_of_the_front_focal_plane(name):
    camera = CAMERAS[name]()
    low, high = geometry.usable_a_range(camera)
    front = geometry.front_focal_plane_mm(camera)
    top = high + 5.0 if math.isfinite(high) else 60.0
    a = np.linspace(low - 20.0, top, 40001)
    d = np.asarray(geometry.slice_distance_mm(camera, a))
    real = np.isfinite(d) & (d > front)
    inside = (a >= low) & (a <= high)
    # the sweep's grid never hits a bound exactly: away from them, the closed form and Eq. 21 agree
    step = a[1] - a[0]
    away = (np.abs(a - low) > step) & (np.abs(a - high) > step if math.isfinite(high) else True)
    np.testing.assert_array_equal(real[away], inside[away])
    assert geometry.slice_distance_mm(camera, low) > 1e12                       # the low end: infinity (to rounding)
    if math.isfinite(high):                                                     # the high end: the front focal plane
        assert geometry.slice_distance_mm(camera, high * (1 - 1e-9)) == pytest.approx(front, rel=1e-6)
    assert (math.isfinite(high)) == (not camera.telecentric)


def test_refusals_name_the_whole_range_low_to_high():
    camera = CAMERAS["sample (at infinity)"]()
    front = geometry.front_focal_plane_mm(camera)
    assert geometry.usable_a_range(camera) == (0.0, math.inf) and front == pytest.approx(100.4)
    whole = "usable: a from +0 (infinity) to +inf (approaching the main lens's front focal plane at 100.4 mm)"
    with pytest.raises(LfprocError, match="beyond infinity") as info:
        geometry.check_usable_a(camera, -5.0, "a")
    assert str(info.value).startswith("a: a=-5 ") and str(info.value).endswith(whole)
    with pytest.raises(LfprocError, match="nearer than the main lens's front focal plane"):
        geometry.check_usable_a(camera, -17.0, "a")      # 67 mm from the sensor: between the lens and f_U
    with pytest.raises(LfprocError, match=r"a=-0\.1 .*\(1 of the 3 slices\)"):
        geometry.check_usable_a(camera, [0.5, -0.1, 2.0], "a")   # a sweep partly outside: refused whole
    geometry.check_usable_a(camera, [0.0, 0.5, 40.0])
    with pytest.raises(LfprocError, match=r"distance_mm: 90 mm is not beyond .* usable: distances beyond 100\.4 mm"):
        geometry.check_usable_distances(camera, [500.0, 90.0])
    geometry.check_usable_distances(camera, [500.0, math.inf])


def test_a_printed_bound_can_be_typed_back():
    camera = CAMERAS["paper f100, b_U = f_U + 10 mm"]()
    low, _ = geometry.usable_a_range(camera)
    text = geometry.usable_range_text(camera, a_high=3.21987)
    printed_low, printed_high = (float(v) for v in
                                 __import__("re").search(r"a from ([+-][\d.]+) .* to ([+-][\d.]+)", text).groups())
    assert low <= printed_low < low + 1e-3 and 3.219 == printed_high
    geometry.check_usable_a(camera, [printed_low, printed_high])
    assert f"({geometry.slice_distance_mm(camera, 3.219):.1f} mm)" in text


def test_a_microscope_has_no_such_bound():
    assert geometry.usable_a_range(_camera("lfm-20x")) == (-math.inf, math.inf)
    geometry.check_usable_a(_camera("lfm-20x"), [-50.0, 50.0])


def test_refocus_refuses_a_depth_range_before_the_front_focal_plane_with_the_range(tmp_path):
    sample = SAMPLES / "sample"
    args = ["--camera", sample / "camera.toml", "--white", sample / "white.png", "-o", tmp_path / "o"]
    proc = run_cli("refocus", sample / "capture.png", *args, "--depth-range", "95:400")
    assert_clean_error(proc, "--depth-range 95:400", "95 mm", "usable: distances beyond 100.4 mm",
                       "a from +0 (infinity)")
    assert not (tmp_path / "o").exists()


# ------------------------------------------------------------------------------- one capture, one range (issue 38)
@pytest.fixture(scope="module")
def sample_lf():
    import lfproc
    sample = SAMPLES / "sample"
    return lfproc.read_light_field(str(sample / "capture.png"), str(sample / "camera.toml"),
                                   white=str(sample / "white.png"))


def _refusal(call) -> str:
    with pytest.raises(LfprocError) as info:
        call()
    message = str(info.value)
    assert "\n" not in message
    return message


def test_every_refusal_of_one_capture_states_its_one_range_low_to_high(sample_lf):
    """Issue 38: ``a=-17`` said "usable: a from +0 (infinity) to +inf" and ``a=400`` on the same capture
    "+0 (infinity) to +7.499 (176.2 mm)". Both now state the capture's one range: the optics' real slices
    (from infinity) narrowed to those whose refocused area covers half the capture, low to high."""
    import lfproc
    from lfproc.refocusing import usable_a_bound
    bound = usable_a_bound(sample_lf.view_mask, sample_lf.lens_shape)
    printed = math.floor(bound * 1000 + 1e-6) / 1000
    near = float(geometry.slice_distance_mm(sample_lf.camera, printed))
    one = f"usable: a from +0 (infinity) to {printed:+.3f}".rstrip("0") + f" ({near:.1f} mm)"
    too_near = _refusal(lambda: lfproc.focal_stack(sample_lf, a=[-17.0]))
    too_far = _refusal(lambda: lfproc.focal_stack(sample_lf, a=[400.0]))
    beyond = _refusal(lambda: lfproc.focal_stack(sample_lf, a=[-0.5, 1.0]))
    assert "a=-17 focuses 67.0 mm from the sensor, nearer than the main lens's front focal plane" in too_near
    assert "at a=400 only 0 %" in too_far and "a=-0.5 focuses beyond infinity" in beyond
    for message in (too_near, too_far, beyond):
        assert message.endswith(one), message
    # asked in mm from the sensor: refused in mm, the same range in distances, low to high
    by_distance = _refusal(lambda: lfproc.focal_stack(sample_lf, distance_mm=[150.0]))
    assert "at distance_mm=150 mm only 0 %" in by_distance
    assert by_distance.endswith(f"usable: distance_mm from {near:.1f} mm to infinity (a from {printed:+.3f} to +0)"
                                .replace(f"{printed:+.3f}", f"{printed:+.3f}".rstrip("0")))


def test_a_microscope_capture_is_refused_in_the_unit_asked(tmp_path):
    """Issue 38: ``z_um=[5000]`` was refused "at a=41.2045 only 0 % ... usable: a from -11.666 (z = -1416 um)";
    asked in µm it is refused in µm, with the range in µm (µm in the text, ``z_um`` as the argument)."""
    import lfproc
    from scopefile import write_tiny_lfm
    folder = write_tiny_lfm(tmp_path)
    lf = lfproc.read_light_field(str(folder / "capture.tif"), str(folder / "lfm.toml"), white=str(folder / "white.tif"))
    message = _refusal(lambda: lfproc.focal_stack(lf, z_um=[5000.0]))
    assert "at z_um=5000 µm only 0 %" in message and "a=" not in message.split("usable:")[0]
    low, high, a_low, a_high = re.search(r"usable: z_um from ([+-][\d.]+) µm to ([+-][\d.]+) µm \(a from "
                                         r"([+-][\d.]+) to ([+-][\d.]+)\)$", message).groups()
    assert float(low) == -float(high) and float(high) > 0 and float(a_low) == -float(a_high)
    # the same capture asked in a: the same range, in a with each end's z
    in_a = _refusal(lambda: lfproc.focal_stack(lf, a=[400.0]))
    assert in_a.endswith(f"usable: a from {a_low} (z = {low} µm) to {a_high} (z = {high} µm)"), in_a
