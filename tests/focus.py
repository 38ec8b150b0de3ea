"""A camera with its main lens focused elsewhere (:func:`lfproc.io.focused_at`)."""

from lfproc.io import focused_at as focused  # noqa: F401
