"""A microscope objective given by its surfaces (issue 37, left over from issue 33): an immersion objective,
sample side first, in water or oil, behind the same interface as every main optics.

The reference is optiland's own paraxial analysis of the same objectives it ships (its 60x and 20x samples,
reversed with ``Optic.flip`` so that the sample side comes first, the sample medium set to water or oil): the
focal length and front focal point (the native object plane), the object-space NA of the paraxial marginal
ray through the stop, the lateral magnification with a tube lens placed with its front focal plane at the
objective's back focal plane, and, for refocusing, where an object moved off the native plane is imaged
(optiland's paraxial image solve), whose image shift w behind the micro lens array is slice a = w·δ/p_m.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import lfproc
from lfproc import geometry
from lfproc.camera import Camera, Microscope

import optiland.materials as optiland_materials  # noqa: E402  (the test extra installs it: the independent reference must not be skipped)
from optiland.samples.microscopes import Microscope20x, Objective60x  # noqa: E402

#: (optiland sample, sample medium index, stop semi-diameter in the sample's units, tube lens f in the same)
OBJECTIVES = {"60x water": (Objective60x, 1.33, 27.0, 400.0), "20x oil": (Microscope20x, 1.515, 1.6, 200.0)}


def _flipped(kind):
    """The optiland objective sample side first, in its immersion medium (object at infinity still)."""
    cls, index, _, _ = OBJECTIVES[kind]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        optic = cls()
        optic.flip()
        optic.set_material(optiland_materials.IdealMaterial(n=index), 0)
        optic.update_paraxial()
    return optic


def _surfaces_toml(optic, stop_semi_diameter) -> str:
    """``[[microscope.surfaces]]`` of the optic's lens surfaces (radius, thickness to the next, index after)."""
    s = optic.surfaces
    positions = np.ravel(s.positions)
    lines = []
    for k in range(1, len(s) - 1):
        index = float(np.ravel(s[k].material_post.n(optic.primary_wavelength))[0])   # as optiland's paraxial
        thickness = float(positions[k + 1] - positions[k]) if k < len(s) - 2 else 0.0
        radius = float(s.radii[k])
        lines += ["[[microscope.surfaces]]", f"radius_mm = {'inf' if np.isinf(radius) else repr(radius)}",
                  f"thickness_mm = {thickness!r}", f"index = {index!r}"]
        if s[k].is_stop:
            lines += [f"semi_diameter_mm = {stop_semi_diameter!r}", "stop = true"]
    return "\n".join(lines) + "\n"


def _camera(kind, extra=""):
    _, index, stop, f_tube = OBJECTIVES[kind]
    text = (f'name = "{kind}"\n[sensor]\npixel_pitch_mm = 0.0065\n[mla]\npitch_mm = 0.125\nfocal_length_mm = 2.5\n'
            f'[microscope]\nimmersion_index = {index}\ntube_lens_focal_length_mm = {f_tube}\nwavelength_nm = 587.6\n'
            f'{extra}' + _surfaces_toml(_flipped(kind), stop))
    return Camera.from_toml_string(text, f"{kind}.toml")


def _with_tube_lens(kind):
    """The optiland objective with the object at its front focal point and a paraxial tube lens whose front
    focal plane is the objective's back focal plane; the image surface in the tube lens's back focal plane."""
    optic = _flipped(kind)
    _, _, stop, f_tube = OBJECTIVES[kind]
    s = optic.surfaces
    n = len(s)
    positions = np.ravel(s.positions)
    back_focus = positions[-1] + float(optic.paraxial.F2())          # optiland gives F2 from the image surface
    front_focus = float(optic.paraxial.F1())                          # and F1 from the first vertex
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        optic.set_thickness(back_focus + f_tube - positions[n - 2], n - 2)
        optic.surfaces.add(index=n - 1, surface_type="paraxial", f=f_tube, thickness=f_tube)
        optic.set_thickness(-front_focus, 0)
        optic.set_aperture("float_by_stop_size", 2.0 * stop)
        optic.update_paraxial()
    return optic, -front_focus


@pytest.mark.parametrize("kind", sorted(OBJECTIVES))
def test_focal_length_native_plane_na_and_magnification_are_optilands(kind):
    camera = _camera(kind)
    scope = camera.main_optics
    objective = scope.objective
    assert isinstance(scope, Microscope) and objective is not None
    optic = _flipped(kind)
    _, index, _, f_tube = OBJECTIVES[kind]
    assert objective.object_index == index == scope.immersion_index
    assert objective.focal_length_mm == pytest.approx(float(optic.paraxial.f2()), rel=1e-9)
    assert objective.front_focal_plane_mm == pytest.approx(float(optic.paraxial.F1()), rel=1e-9)   # native plane
    assert objective.front_principal_plane_mm == pytest.approx(float(optic.paraxial.P1()), rel=1e-9, abs=1e-9)
    full, _ = _with_tube_lens(kind)
    y, u = full.paraxial.marginal_ray()
    assert scope.numerical_aperture == pytest.approx(index * float(np.ravel(u)[0]), rel=1e-9)   # n·u of the marginal ray
    assert scope.objective_magnification == pytest.approx(-float(full.paraxial.magnification()), rel=1e-9)
    assert scope.objective_magnification == pytest.approx(f_tube / objective.focal_length_mm, rel=1e-12)
    # the transfer from the native plane to the MLA is afocal and imaging, −M laterally (the ideal objective's)
    t = scope.transfer()
    assert t.A == pytest.approx(-scope.objective_magnification, rel=1e-9) and t.index == index
    assert abs(t.B) < 1e-9 * f_tube and abs(t.C) < 1e-9 / f_tube


@pytest.mark.parametrize("kind", sorted(OBJECTIVES))
def test_refocus_tags_are_where_optiland_images_the_depth(kind):
    camera = _camera(kind)
    full, object_distance = _with_tube_lens(kind)
    mla = float(np.ravel(full.surfaces.positions)[-1])                 # the tube lens's back focal plane
    delta = camera.sample_pitch_mm / camera.mla_focal_length_mm
    step = 1e-3 * camera.main_optics.objective_focal_length_mm         # depths around a focal length / 1000
    for dz in (-3 * step, -step, 0.5 * step, 2 * step):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            full.set_thickness(object_distance - dz, 0)                # dz nearer the objective
            full.update_paraxial()
            full.image_solve()
        w = float(np.ravel(full.surfaces.positions)[-1]) - mla          # the image, behind the MLA
        a = w * delta / camera.mla_pitch_mm                            # the paper's w = a·p_m/δ
        geo = geometry.slice_geometry(camera, a)
        assert geo.z_um == pytest.approx(dz * 1000.0, rel=1e-7), dz
        assert float(geometry.position_parameter(camera, dz * 1000.0)) == pytest.approx(a, rel=1e-7)
        assert geo.z_far_um < geo.z_um < geo.z_near_um


def test_the_camera_file_of_a_prescribed_objective():
    camera = _camera("60x water")
    scope = camera.main_optics
    text = camera.to_toml()
    assert "[[microscope.surfaces]]" in text and f"objective_magnification = {scope.objective_magnification!r}" in text
    again = Camera.from_toml_string(text, "again")
    assert again == camera and again.to_toml() == text
    # M and NA written by hand must be the surfaces' (0.1 %), as a main lens's cardinal points
    ok = _camera("60x water", f"objective_magnification = {scope.objective_magnification * 1.0005}\n")
    assert ok.main_optics.objective_magnification == scope.objective_magnification
    with pytest.raises(lfproc.LfprocError, match="microscope.numerical_aperture = 0.9 disagrees with the "
                                                 "prescription's numerical aperture from its surfaces"):
        _camera("60x water", "numerical_aperture = 0.9\n")
    with pytest.raises(lfproc.LfprocError, match="stop .* needs semi_diameter_mm"):
        Camera.from_toml_string(text.replace("semi_diameter_mm = 27.0\n", ""), "no-stop.toml")
    with pytest.raises(lfproc.LfprocError, match="keep one"):
        Camera.from_toml_string(text.replace("[microscope]\n", '[microscope]\nprescription = "x.zmx"\n'), "both")


def test_an_objective_from_a_zmx_file_is_the_inline_one(tmp_path):
    """``[microscope] prescription = "objective.zmx"``: the same surfaces as a Zemax file (model glasses), the
    sample medium from ``immersion_index``."""
    inline = _camera("60x water")
    objective = inline.main_optics.objective
    rows = ["VERS 140101 0 0", "MODE SEQ", "UNIT MM X W X CM MR CPMM", "SURF 0", "  TYPE STANDARD", "  CURV 0.0",
            "  DISZ INFINITY"]
    for k, surface in enumerate(objective.surfaces, 1):
        rows += [f"SURF {k}"] + (["  STOP"] if surface.stop else []) + [
            "  TYPE STANDARD", f"  CURV {0.0 if np.isinf(surface.radius_mm) else 1.0 / surface.radius_mm!r}",
            f"  DISZ {surface.thickness_mm!r}"]
        if surface.index != 1.0:
            rows.append(f"  GLAS ___BLANK 1 0 {surface.index!r} 5.0E+1 0 0 0 0 0 0")
        if surface.semi_diameter_mm is not None:
            rows.append(f"  DIAM {surface.semi_diameter_mm!r}")
    rows += [f"SURF {len(objective.surfaces) + 1}", "  TYPE STANDARD", "  CURV 0.0", "  DISZ 0.0"]
    (tmp_path / "objective.zmx").write_text("\n".join(rows) + "\n")
    text = inline.to_toml().split("[[microscope.surfaces]]")[0] + 'prescription = "objective.zmx"\n'
    text += inline.to_toml().split("[decode]")[1].join(("[decode]", ""))
    (tmp_path / "camera.toml").write_text(text)
    from_file = Camera.from_toml(tmp_path / "camera.toml")
    read = from_file.main_optics.objective
    assert read.object_index == 1.33 and [s.stop for s in read.surfaces] == [s.stop for s in objective.surfaces]
    for field in ("radius_mm", "thickness_mm", "index"):       # the file holds curvatures: R to the last bits
        np.testing.assert_allclose([getattr(s, field) for s in read.surfaces],
                                   [getattr(s, field) for s in objective.surfaces], rtol=1e-14)
    assert from_file.main_optics.numerical_aperture == pytest.approx(inline.main_optics.numerical_aperture, rel=1e-13)


def test_a_prescribed_objective_refocuses_and_tags_like_any_microscope():
    camera = _camera("20x oil")
    lf = lfproc.LightField.from_views(np.ones((camera.m_hat, camera.m_hat, 12, 12, 1), np.float32), camera)
    fs = lfproc.focal_stack(lf, z_um=[-2.0, 0.0, 3.0])
    np.testing.assert_allclose(fs.z_um, [-2.0, 0.0, 3.0], rtol=1e-12, atol=1e-12)
    assert fs.records()[0].keys() >= {"a", "z_um", "z_near_um", "z_far_um", "dof_um", "refocus_shifts"}
