"""The colour scale of depth maps: viridis (perceptually uniform, readable in grey and by most colour-blind
viewers), far = dark purple, near = yellow; unknown depths are mid grey.

One scale for the depth preview (`lfproc.depth_map`) and the viewer (`lfproc.viewer`); numpy only, so both
stages import it from here (`lfproc.outputs` re-exports it under the same names)."""

from __future__ import annotations

import numpy as np

#: viridis sampled at 0, 1/8, …, 1 (RGB, 0–255), interpolated linearly in between
DEPTH_COLOURS = ((68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141), (39, 173, 129),
                 (92, 200, 99), (170, 220, 50), (253, 231, 37))
UNKNOWN_COLOUR = (128, 128, 128)


def colour_scale(values) -> np.ndarray:
    """RGB uint8 of ``values`` in [0, 1] (clipped) on :data:`DEPTH_COLOURS`; NaN → :data:`UNKNOWN_COLOUR`."""
    values = np.asarray(values, dtype=np.float64)
    anchors = np.asarray(DEPTH_COLOURS, dtype=np.float64)
    stops = np.linspace(0.0, 1.0, len(anchors))
    known = np.isfinite(values)
    t = np.clip(np.where(known, values, 0.0), 0.0, 1.0)
    rgb = np.stack([np.interp(t, stops, anchors[:, ch]) for ch in range(3)], axis=-1)
    rgb[~known] = UNKNOWN_COLOUR
    return np.round(rgb).astype(np.uint8)
