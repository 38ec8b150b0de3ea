"""A colour-mapped preview of a depth map with a legend in metres (numpy and Pillow only).

Colour follows the inverse distance (proportional to the refocus parameter and to disparity, so equal
steps of colour are equal steps of parallax) on the colour scale the viewer uses too
(:func:`lfproc.colours.colour_scale`: viridis, far dark purple, near yellow); lenses no light reached are
black, lit lenses whose depth is unknown grey. The legend is a colour bar with ticks at round values of its
unit: metres from the sensor, or µm from a microscope's native object plane.
"""

from __future__ import annotations

import math

import numpy as np

from ..colours import UNKNOWN_COLOUR as UNKNOWN_RGB

#: lenses no light reached (`lfproc.depth.lit_lenses`): their depth is unknown for want of light
NO_LIGHT_RGB = (0, 0, 0)
from ..colours import colour_scale

#: the preview's depth map is enlarged (Lanczos, unknown lenses kept unknown: :func:`enlarge_scale`) to about
#: this many pixels on its long side
TARGET_SIZE_PX = 480


def colour_map(t: np.ndarray) -> np.ndarray:
    """``t`` in [0, 1] (0 far, 1 near) → uint8 RGB ``t.shape + (3,)``: the viewer's scale (one scale for both)."""
    return colour_scale(np.clip(np.nan_to_num(np.asarray(t, dtype=np.float64)), 0.0, 1.0))


def display_range_mm(distance_mm: np.ndarray) -> tuple[float, float]:
    """Nearest and farthest distance shown: the 1st and 99th percentile of the known distances."""
    known = distance_mm[np.isfinite(distance_mm)]
    if known.size == 0:
        return (1000.0, 2000.0) if not np.isinf(distance_mm).any() else (1000.0, math.inf)
    near, far = (float(v) for v in np.percentile(known, [1, 99]))
    if np.isinf(distance_mm).any():
        far = math.inf
    if far <= near:
        far = near * 1.1
    return near, far


def _nice_ticks(near_mm: float, far_mm: float, count: int = 5) -> list[float]:
    """Round distances (mm) spread evenly in inverse distance between near and far."""
    inv_near, inv_far = 1.0 / near_mm, (0.0 if math.isinf(far_mm) else 1.0 / far_mm)
    ticks = []
    for inv in np.linspace(inv_near, inv_far, count):
        if inv <= 0:
            ticks.append(math.inf)
            continue
        d = 1.0 / inv
        digits = 1 - math.floor(math.log10(d / 1000.0))
        value = round(d / 1000.0, max(digits, 0)) * 1000.0
        if near_mm <= value <= far_mm and value not in ticks:
            ticks.append(value)
    return ticks


def _label(distance_mm: float) -> str:
    if math.isinf(distance_mm):
        return "inf"
    metres = distance_mm / 1000.0
    return f"{metres:.3g} m"


def _distance_scale(distance_mm: np.ndarray):
    """(t per lens, [(t, label)] ticks, title): inverse distance, 1 at the nearest shown distance; ticks at round
    distances (and ``inf`` where the far end is infinity)."""
    near, far = display_range_mm(distance_mm)
    inv_near, inv_far = 1.0 / near, (0.0 if math.isinf(far) else 1.0 / far)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (1.0 / distance_mm - inv_far) / (inv_near - inv_far)
    ends = [far] if math.isinf(far) else []
    ticks = [((0.0 if math.isinf(d) else 1.0 / d) - inv_far, _label(d)) for d in ends + _nice_ticks(near, far)]
    return t, [(v / (inv_near - inv_far), label) for v, label in ticks], "distance"


def round_ticks(lo: float, hi: float, count: int = 5) -> tuple[list[float], float]:
    """``(ticks, step)``: the multiples of a round step (1, 2 or 5 times a power of ten) inside [lo, hi], the
    step the largest that gives at least ``count - 1`` of them (about ``count``)."""
    span = float(hi - lo)
    if not span > 0:
        return [float(lo)], 1.0
    step = 10.0 ** math.floor(math.log10(span))
    while True:
        for factor in (5.0, 2.0, 1.0):
            candidate = step * factor
            first, last = math.ceil(lo / candidate - 1e-9), math.floor(hi / candidate + 1e-9)
            if last - first + 1 >= max(count - 1, 2):
                return [k * candidate + 0.0 for k in range(first, last + 1)], candidate
        step /= 10.0


def _um(z: float, step: float) -> str:
    """A legend's z at a round value: signed, as many decimals as the step has (``"+20 µm"``, ``"-0.5 µm"``)."""
    decimals = max(0, -math.floor(math.log10(step) + 1e-9))
    return f"{z:+.{decimals}f} µm" if z else "0 µm"


def _z_scale(z_um: np.ndarray):
    """(t per lens, ticks, title) of a microscope's depth in µm: linear in z, 1 nearest the objective; ticks at
    round values."""
    known = z_um[np.isfinite(z_um)]
    lo, hi = (float(v) for v in np.percentile(known, [1, 99])) if known.size else (-1.0, 1.0)
    if hi <= lo:
        lo, hi = lo - 1.0, hi + 1.0
    t = (z_um - lo) / (hi - lo)
    values, step = round_ticks(lo, hi)
    return t, [((z - lo) / (hi - lo), _um(z, step)) for z in values], "z (µm)"


def enlarge_scale(t: np.ndarray, unknown: np.ndarray, scale: int, unlit: np.ndarray | None = None) -> np.ndarray:
    """uint8 RGB of the colour position ``t`` per lens enlarged ``scale`` times, unknown lenses kept unknown.

    The known lenses are resampled with OpenCV's Lanczos-4 kernel (as the other previews,
    :func:`lfproc.outputs.upscale`), after each unknown lens took its nearest known lens's value, so that
    no unknown value leaks into the colours around it; every display pixel whose nearest lens is unknown
    is then grey (:data:`lfproc.outputs.UNKNOWN_COLOUR`), or black (:data:`NO_LIGHT_RGB`) where ``unlit``
    marks it: unknown stays unknown, exactly where it was.
    """
    t = np.asarray(t, dtype=np.float64)
    unknown = np.asarray(unknown, bool) | ~np.isfinite(t)
    dark = np.zeros(t.shape, bool) if unlit is None else np.asarray(unlit, bool) & unknown
    if scale == 1 or unknown.all():
        rgb = colour_map(np.nan_to_num(t))
        rgb[unknown] = UNKNOWN_RGB
        rgb[dark] = NO_LIGHT_RGB
        return np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1)
    import cv2
    from scipy.ndimage import distance_transform_edt

    filled = t
    if unknown.any():
        nearest = distance_transform_edt(unknown, return_distances=False, return_indices=True)
        filled = t[tuple(nearest)]
    ny, nx = t.shape
    smooth = cv2.resize(filled.astype(np.float32), (nx * scale, ny * scale), interpolation=cv2.INTER_LANCZOS4)
    rgb = colour_map(smooth)
    rgb[np.repeat(np.repeat(unknown, scale, axis=0), scale, axis=1)] = UNKNOWN_RGB
    rgb[np.repeat(np.repeat(dark, scale, axis=0), scale, axis=1)] = NO_LIGHT_RGB
    return rgb


def preview_image(distance_mm: np.ndarray | None, z_um: np.ndarray | None = None,
                  unlit: np.ndarray | None = None) -> np.ndarray:
    """uint8 RGB ``(H, W, 3)``: the enlarged colour-mapped depth map with a legend on its right.

    ``z_um`` (a microscope's depth from the native object plane) instead of ``distance_mm``: colour
    linear in z, yellow nearest the objective, legend in µm. ``unlit`` (``(Ny, Nx)`` booleans, the lenses no
    light reached): drawn black, apart from the grey of lit lenses whose depth is unknown.
    """
    from PIL import Image, ImageDraw

    from ..io import label_font, label_text

    font = label_font()
    values = distance_mm if z_um is None else z_um
    t, ticks, title = _distance_scale(distance_mm) if z_um is None else _z_scale(z_um)
    ticks, title = [(v, label_text(label, font)) for v, label in ticks], label_text(title, font)
    ny, nx = values.shape
    scale = max(1, round(TARGET_SIZE_PX / max(ny, nx)))
    unknown = np.isnan(values)
    body = enlarge_scale(t, unknown, scale, unlit)
    height = max(body.shape[0], 160)
    bar_w, margin = 18, 10
    notes = ["grey: unknown"] + (["black: no light"] if unlit is not None and (unknown & unlit).any() else [])
    words = [label for _, label in ticks] + [title] + notes
    label_w = max(80, max(_width(font, w) for w in words) + 12)   # every label inside the picture
    canvas = Image.new("RGB", (body.shape[1] + margin + bar_w + label_w, height + 2 * margin), (255, 255, 255))
    canvas.paste(Image.fromarray(body), (0, margin))
    line_h = _height(font)
    bar_h = height - 12 - 12 * len(notes) - 8   # room below the bar for the bottom tick's lower half and the notes
    bar_t = np.linspace(1.0, 0.0, bar_h)[:, None].repeat(bar_w, axis=1)   # near at the top
    x0, y0 = body.shape[1] + margin, margin + 12
    canvas.paste(Image.fromarray(colour_map(bar_t)), (x0, y0))
    draw = ImageDraw.Draw(canvas)
    draw.text((x0, margin - 8), title, fill=(0, 0, 0), font=font)
    drawn: list[int] = []
    for position, label in ticks:
        y = y0 + round((1.0 - position) * (bar_h - 1))
        if any(abs(y - other) < line_h + 3 for other in drawn):   # labels never overlap
            continue
        drawn.append(y)
        draw.line([(x0 + bar_w, y), (x0 + bar_w + 4, y)], fill=(0, 0, 0))
        draw.text((x0 + bar_w + 6, y - 5), label, fill=(0, 0, 0), font=font)
    for row, note in enumerate(notes):
        draw.text((x0, y0 + bar_h + 8 + 12 * row), note, fill=(80, 80, 80), font=font)
    return np.asarray(canvas)


def _width(font, text: str) -> int:
    left, _, right, _ = font.getbbox(text)
    return int(math.ceil(right - min(left, 0)))


def _height(font) -> int:
    _, top, _, bottom = font.getbbox("0123456789-+.e µm")
    return int(math.ceil(bottom - min(top, 0)))


def write_preview(path: str, distance_mm: np.ndarray | None, z_um: np.ndarray | None = None,
                  unlit: np.ndarray | None = None) -> None:
    """Write :func:`preview_image` as an 8-bit PNG, atomically, tagged as a depth map's preview (``lfproc info``)."""
    from ..io import write_png_preview

    legend = "distance (m)" if z_um is None else "z (µm)"
    write_png_preview(path, preview_image(distance_mm, z_um, unlit), {"preview": "depth map", "legend": legend})
