"""lfproc: Standard Plenoptic Camera light fields — refocusing, viewpoints, and the metric geometry of each.

The public API is what ``lfproc.__all__`` lists (docs/api.md): the calls of the contract (``read_camera``,
``calibrate_white``, ``read_light_field``, ``prepare_decoding``, ``focal_stack``, ``view_stack``, ``depth_map``,
``deconvolve``, ``prepare_deconvolution``, ``refocus``, ``slice_sharpness``, ``viewpoints``, ``with_aperture``,
``focused_at``), their results, and two subpackages:
:mod:`lfproc.geometry` (the paper's metric model, without images) and :mod:`lfproc.simulate` (rendered test
scenes). Every other package is internal (its docstring says so).

Importing lfproc is cheap: numba, OpenCV and OpenImageIO load only when a function that needs them is first
used (``lfproc.refocus``, the readers and writers, decoding).
"""

from importlib import import_module

from .camera import Camera
from .errors import LfprocError, LfprocWarning
from .grid import LensGrid
from .lightfield import LightField
from .sample_data import sample_path
from .viewpoints import viewpoints, with_aperture

from ._version import __version__

# public name -> (module, attribute), imported on first access (PEP 562)
_LAZY = {
    "refocus": ("lfproc.refocusing", "refocus"),
    "read_camera": ("lfproc.io", "read_camera"),
    "read_light_field": ("lfproc.api", "read_light_field"),
    "calibrate_white": ("lfproc.api", "calibrate_white"),
    "prepare_decoding": ("lfproc.api", "prepare_decoding"),
    "DecodeSetup": ("lfproc.api", "DecodeSetup"),
    "focal_stack": ("lfproc.api", "focal_stack"),
    "FocalStack": ("lfproc.api", "FocalStack"),
    "view_stack": ("lfproc.api", "view_stack"),
    "ViewStack": ("lfproc.api", "ViewStack"),
    "depth_map": ("lfproc.api", "depth_map"),
    "DepthMap": ("lfproc.depth", "DepthMap"),
    "deconvolve": ("lfproc.api", "deconvolve"),
    "prepare_deconvolution": ("lfproc.api", "prepare_deconvolution"),
    "slice_sharpness": ("lfproc.refocusing", "slice_sharpness"),
    "focused_at": ("lfproc.io", "focused_at"),
    "Volume": ("lfproc.api", "Volume"),
    "geometry": ("lfproc.geometry", None),
    "simulate": ("lfproc.simulate", None),
}

__all__ = ["Camera", "LensGrid", "LightField", "LfprocError", "LfprocWarning", "viewpoints", "with_aperture",
           "sample_path", *_LAZY]


def __getattr__(name):
    if name not in _LAZY:
        raise AttributeError(f"module 'lfproc' has no attribute {name!r}")
    module_name, attr = _LAZY[name]
    module = import_module(module_name)
    value = module if attr is None else getattr(module, attr)
    globals()[name] = value
    return value
