"""Depth from focus on the lens grid: where is each point sharpest in a sweep of refocused slices?

A shift-and-sum slice (Eq. 9) of parameter ``a`` is sharp where the scene lies at the slice's
distance d_a (Eq. 21) and blurred elsewhere, the blur growing with |a − a_scene|·(2c + 1) lenses
(every view moves by a·(k − c) lenses). So a sweep of slices over ``a``, a local sharpness measure
per slice (gradient energy of the luminance, summed over a small window) and, per lens, the ``a``
where it peaks give the scene's refocus parameter and, through Eq. 21, its distance. The sweep
steps by a third of a slice's depth of field in ``a`` (which is about 1/c wide at a = 0, see
:func:`lfproc.geometry.slice_geometry`), and a parabola through the peak and its neighbours refines
it. The sweep refocuses the luminance of every other view only (:func:`sweep_lightfield`).
Textureless regions have no sharpness peak; their confidence (1 − median/peak of the
sharpness along the sweep) is low.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import geometry
from ..lightfield import LightField

#: most slices in a sweep (a third of a DOF per step otherwise)
MAX_SWEEP = 64
#: default span of the sweep in a, from the slice focused at infinity towards the camera
DEFAULT_SPAN_A = 3.0


@dataclass(frozen=True, eq=False)
class FocusDepth:
    """Per-lens result of :func:`depth_from_focus`; arrays ``(Ny, Nx)`` on the light field's lens grid.

    Attributes
    ----------
    a : refined refocus parameter where each lens is sharpest
    distance_mm : its distance from the sensor (Eq. 21), ``inf`` at or beyond infinity's ``a``
    confidence : 0 (no sharpness peak: flat or noisy) to 1 (a clear peak)
    sweep_a : the refocus parameters of the sweep
    method : how the depths were found
    min_confidence : below it a lens's depth is a guess (grey in the depth map, not used for planning)
    """

    a: np.ndarray
    distance_mm: np.ndarray
    confidence: np.ndarray
    sweep_a: np.ndarray
    method: str = "depth from focus"
    min_confidence: float = 0.3


def sweep_range(camera, lens_shape, a_values=None) -> tuple[float, float]:
    """The ``a`` interval to sweep.

    With ``a_values``: their range widened by half a slice's DOF on each side, so that a peak at the
    first or last slice is still a peak. Without: from infinity's ``a`` (Eq. 21 with d = ∞) nearer by
    :data:`DEFAULT_SPAN_A`, within the ``a`` that move the outer views by at most a third of the
    image's smaller side.
    """
    c = max(camera.center_index, 1)
    if a_values is not None and len(a_values):
        margin = 0.5 / c
        return float(np.min(a_values)) - margin, float(np.max(a_values)) + margin
    reach = min(lens_shape) / (3.0 * c)  # |a|·c lenses of shift at the outer views: a third of the image
    a_inf = geometry.infinity_parameter(camera)
    lo = max(a_inf, -reach)
    return lo, max(lo, min(a_inf + DEFAULT_SPAN_A, reach))


def sweep(camera, lo: float, hi: float) -> np.ndarray:
    """Refocus parameters from ``lo`` to ``hi`` a third of a DOF apart (at most :data:`MAX_SWEEP`)."""
    step = 1.0 / (3.0 * max(camera.center_index, 1))
    count = int(np.clip(np.ceil((hi - lo) / step) + 1, 3, MAX_SWEEP))
    return np.linspace(lo, hi, count) if hi > lo else np.array([lo - step, lo, lo + step])


def sweep_lightfield(lf: LightField) -> tuple[LightField, int]:
    """The light field the sweep refocuses: the luminance (mean over channels) of every ``stride``-th view
    about the centre, and that stride (2 from 9 × 9 views on, else 1).

    Refocusing the thinned views at ``stride·a`` moves each of them exactly as refocusing all views at
    ``a`` does (Eq. 9: view k moves by a·(c − k)), so the sharpness peaks at the same ``a``; the outer
    views that set the defocus blur stay, and a 15 × 15 light field is read 4.6 × less.
    """
    m, c = lf.m_hat, lf.center_index
    stride = 2 if m >= 9 else 1
    keep = np.arange(c % stride, m, stride)
    views = lf.views[np.ix_(keep, keep)]
    grey = views[..., 0].copy() if lf.channels == 1 else views.mean(axis=-1, dtype=np.float32)
    return LightField.from_views(grey[..., None]), stride


def sharpness(stack: np.ndarray, window: int) -> np.ndarray:
    """Gradient energy of each slice of a ``(K, Ny, Nx, 1)`` stack, box-summed over ``window`` lenses."""
    from scipy import ndimage

    image = stack[..., 0]
    energy = np.zeros_like(image)
    energy[:, :, 1:-1] = (image[:, :, 2:] - image[:, :, :-2]) ** 2
    energy[:, 1:-1, :] += (image[:, 2:, :] - image[:, :-2, :]) ** 2
    return ndimage.uniform_filter(energy, size=(1, window, window), mode="nearest")


def peak(scores: np.ndarray, sweep_a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per lens: the refined ``a`` of the score's maximum along axis 0, and the peak's confidence."""
    best = np.argmax(scores, axis=0)
    k = np.clip(best, 1, len(sweep_a) - 2)
    take = lambda offset: np.take_along_axis(scores, (k + offset)[None], axis=0)[0]
    left, centre, right = take(-1), take(0), take(1)
    curvature = left - 2.0 * centre + right
    with np.errstate(divide="ignore", invalid="ignore"):
        shift = np.where(curvature < 0, 0.5 * (left - right) / curvature, 0.0)
    shift = np.where(best == k, np.clip(shift, -0.5, 0.5), 0.0)  # a peak at the sweep's end is not refined
    step = sweep_a[1] - sweep_a[0]
    a = sweep_a[best] + shift * step
    top = np.take_along_axis(scores, best[None], axis=0)[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        confidence = np.where(top > 0, 1.0 - np.median(scores, axis=0) / top, 0.0)
    return a, np.clip(np.nan_to_num(confidence), 0.0, 1.0)


def depth_from_focus(lf: LightField, a_values=None, window: int | None = None) -> FocusDepth:
    """Depth from focus of ``lf`` (module docstring) over the ``a`` range of ``a_values`` (default: a
    range from infinity towards the camera, :func:`sweep_range`).

    Parameters
    ----------
    lf : LightField
        With its camera.
    a_values : sequence of float, optional
        Slices whose ``a`` range the sweep covers.
    window : int, optional
        Side of the sharpness window in lenses (default c + 1 rounded up to odd, at least 5).
    """
    from ..refocus import refocus

    camera = lf.camera
    lo, hi = sweep_range(camera, lf.lens_shape, a_values)
    sweep_a = sweep(camera, lo, hi)
    thinned, stride = sweep_lightfield(lf)
    stack = refocus(thinned, stride * sweep_a, interpolation="cubic")
    if window is None:
        window = max(5, camera.center_index + 1) | 1
    a, confidence = peak(sharpness(stack, window), sweep_a)
    a_inf = geometry.infinity_parameter(camera)
    distance = np.where(a <= a_inf, np.inf, geometry.slice_distance_mm(camera, np.maximum(a, a_inf)))
    return FocusDepth(a.astype(np.float32), distance.astype(np.float32), confidence.astype(np.float32), sweep_a)
