"""Checks of refocus parameters shared by :func:`lfproc.focal_stack` and the commands (which word the
argument as their flag: ``what="--a"``).

Every refusal of one light field states one usable range: the optics' real slices
(:func:`lfproc.geometry.usable_a_range`) narrowed to those whose refocused area covers half the capture
(:func:`lfproc.refocusing.usable_a_bound`), low to high, in the terms of the argument given (``a``, or positions
such as ``z_um``).
"""

from __future__ import annotations


import numpy as np

from ..errors import LfprocError, warn


def check_slices(camera, a_values, lens_shape, view_mask, source: str, what: str = "a", asked=None) -> None:
    """Refuse slices that image no real object (:func:`lfproc.geometry.check_usable_a`) or whose refocused area
    is under half the image (a garbage a), before any work, with the one usable range of this light field.

    Parameters
    ----------
    camera : Camera
    a_values : sequence of float
    lens_shape : (Ny, Nx)
        The light field's lenses.
    view_mask : (m̂, m̂) bool array or None
        The views the slices sum (all when ``None``).
    source : str
        The capture, named in the message.
    what : str
        The argument the slices came from (``a``, ``distance_mm``, ``z_um``; a command's ``--a``).
    asked : array_like, optional
        The values as given, where ``what`` names positions (the message then speaks in them).
    """
    from .. import geometry
    from ..refocusing import MIN_REFOCUSED_AREA, refocused_fraction, usable_a_bound

    mask = camera.m_hat if view_mask is None else view_mask
    try:
        geometry.check_usable_a(camera, a_values, what, asked=asked, source=source)
    except LfprocError:   # refused: say so with this light field's range (its bound is found only to be said)
        bound = usable_a_bound(mask, lens_shape)
        geometry.check_usable_a(camera, a_values, what, -bound, bound, asked, source)
    a = np.atleast_1d(np.asarray(a_values, dtype=np.float64))
    share = refocused_fraction(a, mask, lens_shape)
    bad = np.flatnonzero(share < MIN_REFOCUSED_AREA)
    if not len(bad):
        return
    bound = usable_a_bound(mask, lens_shape)
    space = camera.main_optics.object_space
    name = what if what == space.position_key else "a"
    given = f"a={a[bad[0]]:g}" if asked is None else f"{what}={np.atleast_1d(asked)[bad[0]]:g} {space.symbol}"
    n = int(np.sum(mask)) if np.ndim(mask) else int(mask) ** 2
    raise LfprocError(f"{source}: at {given} only {100 * share[bad[0]]:.0f} % of the {lens_shape[0]}x{lens_shape[1]}"
                      f"-lens slice averages at least half of the {n} summed views (the others shift off the "
                      f"capture); usable: {geometry.usable_range_text(camera, -bound, bound, name)}")


def check_view_coverage(camera, a_values, lens_shape, source: str, view_mask=None, what: str = "a",
                        asked=None) -> None:
    """Refuse slices that image nothing or whose refocused area is under half the image (:func:`check_slices`);
    warn (:class:`lfproc.LfprocWarning`) where most pixels miss some views."""
    from ..refocusing import full_view_fraction

    check_slices(camera, a_values, lens_shape, view_mask, source, what, asked)
    m = camera.m_hat
    share = full_view_fraction(a_values, m, lens_shape)
    thin = [a for a, f in zip(a_values, share) if f < 0.5]
    if thin:
        worst = max(thin, key=abs)
        warn(f"{source}: in {len(thin)} slice(s) (up to a={worst:+.3g}) fewer than half the pixels average "
             f"all views: a border band of up to {abs(worst) * (m - 1) / 2:.0f} lenses is less refocused")


def check_z_step(camera, a_values) -> None:
    """Warn (:class:`lfproc.LfprocWarning`, once) when slices form an evenly spaced stack in the optics' object
    space whose step is far finer than their depth of field (:func:`lfproc.geometry.step_advice`): what
    :func:`lfproc.focal_stack` and every command that plans slices say, in the same words."""
    from .. import geometry

    if len(a_values) < 3:
        return
    positions = np.sort(geometry.slice_geometry(camera, np.asarray(a_values, dtype=np.float64)).depth)
    steps = np.diff(positions)
    if not (np.all(np.isfinite(steps)) and steps[0] > 0 and np.allclose(steps, steps[0], rtol=1e-6, atol=0.0)):
        return
    advice = geometry.step_advice(camera, float(steps[0]), float(positions[0]), float(positions[-1]))
    if advice:
        warn(advice)
