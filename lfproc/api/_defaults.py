"""The defaults the commands and the Python API share (one place, so they cannot drift)."""

#: how refocused slices read positions between lenses: the commands' ``--interpolation`` default and
#: :func:`lfproc.focal_stack`'s (the interpolating cubic spline holds the sharpest slice at the true ``a``;
#: :mod:`lfproc.refocus`). :func:`lfproc.refocus` on arrays keeps its own contract default, ``"linear"``.
DEFAULT_INTERPOLATION = "cubic-spline"
