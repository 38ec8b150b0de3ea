"""Metric depth from one light field: ``lfproc.depth(lf)`` and the outputs of ``lfproc depth``.

Public names: :func:`depth` (also reachable as ``lfproc.depth(lf, ...)``), :class:`DepthMap`, :func:`summary_line` and
:func:`write_depth_outputs` (the files of ``lfproc depth`` for one capture); :func:`write_preview` and
:func:`preview_image` (the colour-mapped depth preview with its legend, also used by ``lfproc export``);
:func:`lit_lenses` and :data:`UNLIT_FRACTION` (no depth where no light fell); :data:`MIN_CONFIDENCE` and :func:`search_range_a` (the defaults and range checks ``lfproc depth`` applies to its
options before reading a capture). Importing this package
is light; numba and the writers load on first use.
"""

from ._confidence import MIN_CONFIDENCE, UNLIT_FRACTION, lit_lenses
from ._estimate import depth
from ._result import METHOD, DepthMap
from ._outputs import summary_line, write_depth_outputs
from ._preview import preview_image, write_preview
from ._search import search_range_a

__all__ = ["METHOD", "DepthMap", "depth", "summary_line", "write_depth_outputs", "MIN_CONFIDENCE", "search_range_a",
           "preview_image", "write_preview", "UNLIT_FRACTION", "lit_lenses"]
