"""Checks of refocus parameters shared by :func:`lfproc.focal_stack` and the commands (which word the
argument as their flag: ``what="--a"``)."""

from __future__ import annotations

import warnings

import numpy as np

from ..errors import LfprocError, LfprocWarning


def lowest_meaningful_a(camera) -> float:
    """The lowest a of a real slice: the one focused at infinity (:func:`lfproc.geometry.usable_a_range`)."""
    from .. import geometry

    return geometry.usable_a_range(camera)[0]


def check_slice_meaning(camera, a_values, what: str = "a") -> None:
    """Refuse slices that focus beyond infinity or nearer than the main lens's front focal plane
    (:func:`lfproc.geometry.check_usable_a`): a sweep partly outside is refused whole, before any work,
    with the usable range low-to-high in a and in distance (``what`` names the argument: ``a`` from
    Python, ``--a`` from a command)."""
    from .. import geometry

    geometry.check_usable_a(camera, a_values, what)


def check_refocused_area(camera, a_values, lens_shape, view_mask, source: str) -> None:
    """Refuse slices whose refocused area is under half the image (:func:`lfproc.refocus.check_refocused_area`),
    with the usable range low-to-high in a and in distance (narrowed to the real slices)."""
    from .. import geometry
    from ..refocus import check_refocused_area as check

    mask = camera.m_hat if view_mask is None else view_mask
    check(a_values, mask, lens_shape, source, lowest_a=lowest_meaningful_a(camera),
          range_text=lambda lo, hi: geometry.usable_range_text(camera, lo, hi))


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


def check_z_step(camera, a_values) -> None:
    """Warn (:class:`lfproc.LfprocWarning`, once) when a microscope's slices form an evenly spaced z-stack whose
    step is far finer than their depth of field (:func:`lfproc.geometry.z_step_advice`): what
    :func:`lfproc.focal_stack` and every command that plans slices say, in the same words."""
    from .. import geometry

    if camera.object_space.from_sensor or len(a_values) < 3:
        return
    z = np.sort(np.asarray(a_values, dtype=np.float64)) * geometry.z_per_a_um(camera)
    steps = np.diff(z)
    if not (steps[0] > 0 and np.allclose(steps, steps[0], rtol=1e-6, atol=0.0)):
        return
    advice = geometry.z_step_advice(camera, float(steps[0]), float(z[0]), float(z[-1]))
    if advice:
        warnings.warn(advice, LfprocWarning, stacklevel=3)
