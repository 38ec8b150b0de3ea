"""Where is each lens's surface? ``lfproc.depth`` when this installation has it, else depth from focus.

``lfproc.depth`` (the depth stage, ``lfproc/depth/``) combines the variance across views with the
sharpest-slice cue and is several times more accurate than the sharpness peak alone; the viewer uses
it whenever it can be imported, over the same range of ``a`` that depth from focus would sweep. Both
give a :class:`~lfproc.viewer.FocusDepth` record: per-lens ``a`` (NaN = unknown), distance,
confidence, the ``a`` searched and the method's name.
"""

from __future__ import annotations

import numpy as np

from ._focus import FocusDepth, depth_from_focus, sweep_range


def estimate_depth(lf, a_values=None) -> FocusDepth:
    """Per-lens depth of ``lf`` over the ``a`` range of ``a_values`` (default: from infinity nearer)."""
    try:
        from ..depth import depth as depth_map
    except ImportError:  # an lfproc without the depth stage: the sharpness peak alone
        return depth_from_focus(lf, a_values)
    lo, hi = sweep_range(lf.camera, lf.lens_shape, a_values)
    found = depth_map(lf, a_range=(lo, hi))
    known = np.isfinite(found.a)
    return FocusDepth(np.where(known, found.a, np.nan).astype(np.float32),
                      np.where(known, found.distance_mm, np.nan).astype(np.float32),
                      np.where(known, found.confidence, 0.0).astype(np.float32),
                      np.asarray(found.a_searched, dtype=np.float64), "lfproc.depth: " + str(found.method),
                      min_confidence=0.0)  # lfproc.depth marks what it does not know as NaN itself
