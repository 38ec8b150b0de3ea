"""lfproc: Standard Plenoptic Camera light fields — refocusing, viewpoints, and the metric geometry of each.

Importing lfproc is cheap: numba, OpenCV and OpenImageIO load only when a function that needs them
is first used (``lfproc.refocus``, the readers and writers, decoding). ``lfproc.refocus`` is the
function of the contract; its module ``lfproc/refocus.py`` is callable too, so the name works
whichever was imported first.
"""

from importlib import import_module

from .camera import Camera
from .errors import LfprocError, LfprocWarning
from .grid import LensGrid
from .lightfield import LightField
from .sample_data import sample_path
from .viewpoints import viewpoints, with_aperture  # light (numpy only); bound here so the submodule cannot shadow it

from ._version import __version__

# public name -> (module, attribute), imported on first access
_LAZY = {
    "refocus": ("lfproc.refocus", "refocus"),
    "geometry": ("lfproc.geometry", None),
    "simulate": ("lfproc.simulate", None),
    "calibrate": ("lfproc.calibrate", None),
    "decode": ("lfproc.decode", None),
    "io": ("lfproc.io", None),
    "depth": ("lfproc.depth", "depth"),
    # the Python API (contract): light to import, heavy only when called
    "read_camera": ("lfproc.io", "read_camera"),
    "read_light_field": ("lfproc.api", "read_light_field"),
    "calibrate_white": ("lfproc.api", "calibrate_white"),
    "prepare_decoding": ("lfproc.api", "prepare_decoding"),
    "focal_stack": ("lfproc.api", "focal_stack"),
    "view_stack": ("lfproc.api", "view_stack"),
    "depth_map": ("lfproc.api", "depth_map"),
    "deconvolve": ("lfproc.api", "deconvolve"),
}

__all__ = ["Camera", "LensGrid", "LightField", "LfprocError", "LfprocWarning", "viewpoints", "with_aperture", "sample_path", *_LAZY]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module 'lfproc' has no attribute {name!r}")
    module_name, attr = _LAZY[name]
    module = import_module(module_name)
    value = module if attr is None else getattr(module, attr)
    globals()[name] = value
    return value
