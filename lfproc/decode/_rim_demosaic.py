"""Demosaicing inside each micro image that keeps every pixel's own ray, up to the rim.

Bilinear demosaicing reads a red (or blue) value from the red pixels around it, up to a pixel away.
At the rim of a micro image the red pixels beyond it are dark (or belong to the next lens), so the
red value of a rim sample comes from further in: its ray sits up to a pixel inwards of the green
one's, and the outer views of a Bayer capture are not one set of rays (issue 20: on the demo sample
the outer ring read 0.5–0.75 effective pixel inwards in red and blue, however far out it was read).

Here every pixel keeps its own value, devignetted (``capture / white``), and gets the other channels
from the *hue of its micro image*: with ``M_ch`` the white-weighted mean of channel ch over the lens's
own pixels (its cell; a pixel on the cell border counts by its share, :func:`lfproc.decode._cells.cell_shares`),
a pixel of channel a with value ρ gets

    value_ch = M_ch + g · (ρ − M_a),    g = (M_ch + ε) / (M_a + ε) clipped to [1/4, 4]

the lens's mean of ch plus the pixel's own detail scaled by the hue ratio (exact where the hue is
constant over the micro image, as for a tinted texture; where one channel is nearly black, as on a
saturated colour, the clip keeps its noise from being amplified). Texture detail, which carries the
parallax, comes from the pixel itself in every channel; only the hue comes from the whole micro image.
So a rim pixel's three channels all stand for the ray of that one pixel, as a mono sensor's would, and
no channel mixes in a neighbouring micro image. (A hue per micro image means one hue per lens for all
its views: a colour edge that only some views see is rendered with the lens's mean hue, its brightness
detail kept. The kernel is :mod:`._rim_kernel`.)

Every sample is then read with one kernel for all channels and all views: ``K·(ŵ·rgb) / K·ŵ``, ŵ the
white image balanced per Bayer phase (each phase divided by its bright level: the share of the pixel
that is lit) and weighted by the pixel's share in the lens (:func:`lfproc.decode._cells.cell_shares`).
The ray a sample stands for is the ŵ-weighted centroid of K, the same as for a mono sensor, which is
what :func:`lfproc.decode._view_mask.view_sampling` probes.
"""

from __future__ import annotations

import numpy as np

#: channel index of each letter of a Bayer pattern
_CHANNEL = {"R": 0, "G": 1, "B": 2}
#: ε of the hue ratio, in units of the white's bright level (the balanced white is about 1 where lit)
RATIO_FLOOR = 1e-3
#: the hue ratio g is clipped to [1 / RATIO_LIMIT, RATIO_LIMIT]
RATIO_LIMIT = 4.0


def phase_channels(cfa: str) -> np.ndarray:
    """Channel index (0 R, 1 G, 2 B) of each Bayer phase of ``cfa``."""
    return np.array([_CHANNEL[letter] for letter in cfa], dtype=np.uint8)


def phase_levels(white: np.ndarray) -> np.ndarray:
    """The bright level of each Bayer phase of a white mosaic (its 99th percentile): ``(4,)``."""
    levels = np.empty(4)
    for p in range(4):
        sub = white[p // 2::2, p % 2::2]
        step_y, step_x = max(1, sub.shape[0] // 512), max(1, sub.shape[1] // 512)
        levels[p] = float(np.percentile(sub[::step_y, ::step_x], 99)) if sub.size else 0.0
    return levels


def balanced_white(white: np.ndarray, dark_fraction: float) -> tuple[np.ndarray, np.ndarray]:
    """``(ŵ, levels)``: the white mosaic with each Bayer phase divided by its bright level, 0 below
    ``dark_fraction`` (those pixels carry no signal), float32; and the four levels."""
    levels = phase_levels(white)
    levels = np.where(levels > 0, levels, max(float(levels.max()), 1e-30))
    wb = np.asarray(white, dtype=np.float32).copy()
    for p in range(4):
        wb[p // 2::2, p % 2::2] *= np.float32(1.0 / levels[p])
    wb[~(wb >= dark_fraction)] = 0.0
    return wb, levels
