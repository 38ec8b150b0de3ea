"""Metric depth from one light field: the estimate behind ``lfproc.depth_map`` and the outputs of ``lfproc depth``.

:func:`depth` (the plane sweep), :class:`DepthMap` (the one result, also ``lfproc.DepthMap``),
:func:`summary_line`; :func:`write_preview` and :func:`preview_image` (the colour-mapped depth preview with its
legend, also used by ``lfproc export``); :func:`lit_lenses` and :data:`UNLIT_FRACTION` (no depth where no light
fell); :data:`MIN_CONFIDENCE` and :func:`search_range_a` (the defaults and range checks ``lfproc depth`` applies
to its options before reading a capture). Importing this package is light; numba and the writers load on first
use.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._confidence import MIN_CONFIDENCE, UNLIT_FRACTION, lit_lenses
from ._estimate import depth
from ._result import DepthMap
from ._outputs import summary_line
from ._preview import preview_image, write_preview
from ._search import search_range_a
