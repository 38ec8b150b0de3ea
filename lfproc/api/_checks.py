"""Checks of refocus parameters shared by :func:`lfproc.focal_stack` and the commands (which word the
argument as their flag: ``what="--a"``)."""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import LfprocError, LfprocWarning


def lowest_meaningful_a(camera) -> float:
    """The lowest a whose slice is beyond the front focal plane or at infinity (the macro regime below it)."""
    from .. import geometry

    inside = camera.sensor_to_main_lens_mm
    return float(geometry.refocus_parameter(camera, inside + 1e-9 * max(inside, 1.0)))


def check_slice_meaning(camera, a_values, what: str = "a") -> None:
    """Refuse slices focused nearer than the main lens's front focal plane (the paraxial model's macro
    regime, between the lens and f_U in front of it): no object there forms a real image. Slices
    beyond infinity (distance ``inf``) stay allowed; their tags say so."""
    from .. import geometry

    front = camera.sensor_to_main_lens_mm + camera.main_focal_length_mm
    d = np.atleast_1d(geometry.slice_distance_mm(camera, np.asarray(a_values, dtype=np.float64)))
    bad = np.flatnonzero(np.isfinite(d) & (d <= front))
    if len(bad):
        a = float(np.atleast_1d(a_values)[bad[0]])
        raise LfprocError(f"{what}: a={a:g} would focus {d[bad[0]]:.1f} mm from the sensor, nearer than the main "
                          f"lens's front focal plane ({front:.1f} mm), where nothing forms a real image; give "
                          f"a >= {lowest_meaningful_a(camera):+.3g}")


def check_refocused_area(camera, a_values, lens_shape, view_mask, source: str) -> None:
    """Refuse slices whose refocused area is under half the image (:func:`lfproc.refocus.check_refocused_area`),
    with the usable range in a and in distance, far end first."""
    from .. import geometry
    from ..refocus import check_refocused_area as check

    mask = camera.m_hat if view_mask is None else view_mask
    if camera.is_microscope:
        check(a_values, mask, lens_shape, source,
              lambda a: f"z = {float(geometry.slice_geometry(camera, a).z_um):.4g} um")
        return
    check(a_values, mask, lens_shape, source, lambda a: geometry.slice_distance_mm(camera, a),
          lowest_meaningful_a(camera))


def check_view_coverage(camera, a_values, lens_shape, source: str, view_mask=None) -> None:
    """Refuse slices whose refocused area is under half the image (a garbage a); warn
    (:class:`lfproc.LfprocWarning`) where most pixels miss some views."""
    from ..refocus import full_view_fraction

    check_refocused_area(camera, a_values, lens_shape, view_mask, source)
    m = camera.m_hat
    share = full_view_fraction(a_values, m, lens_shape)
    thin = [a for a, f in zip(a_values, share) if f < 0.5]
    if thin:
        worst = max(thin, key=abs)
        warnings.warn(f"{source}: in {len(thin)} slice(s) (up to a={worst:+.3g}) fewer than half the pixels average "
                      f"all views: a border band of up to {abs(worst) * (m - 1) / 2:.0f} lenses is less refocused",
                      LfprocWarning, stacklevel=3)
