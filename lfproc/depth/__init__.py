"""Metric depth from one light field: ``lfproc.depth(lf)`` and the outputs of ``lfproc depth``.

Public names: :func:`depth` (also reachable as ``lfproc.depth(lf, ...)``), :class:`DepthMap`,
:func:`summary_line`, :func:`lit_lenses` (no depth where no light fell) and :func:`write_depth_outputs` (the
files of ``lfproc depth`` for one capture). Importing this package is light; numba and the writers load on
first use.
"""

import sys
import types

from ._confidence import UNLIT_FRACTION, lit_lenses
from ._estimate import METHOD, DepthMap, depth
from ._outputs import summary_line, write_depth_outputs

__all__ = ["METHOD", "DepthMap", "UNLIT_FRACTION", "depth", "lit_lenses", "summary_line", "write_depth_outputs"]


class _CallableModule(types.ModuleType):
    """``import lfproc.depth`` binds the package attribute ``lfproc.depth`` to this package; calling it calls
    :func:`depth`, so ``lfproc.depth(lf)`` works whatever was imported first (as ``lfproc.refocus`` does)."""

    def __call__(self, *args, **kwargs):
        return depth(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
