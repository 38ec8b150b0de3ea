"""The browser viewer: a static page per capture to refocus by clicking, move the viewpoint and read
distances in metres (``lfproc viewer``).

:func:`build_page` writes one capture's page (its slices planned for the scene, the views inside the
aperture, a depth map (:func:`lfproc.depth_map`) and the geometry of everything, see ``_build``); the slices and
views are the Python API's (:func:`lfproc.focal_stack`, :func:`lfproc.view_stack`) with their tags; :func:`write_index`
links several; :func:`serve` serves a folder on 127.0.0.1 (from a background thread; it returns the running
server, whose ``url`` the command prints). Pages are self-contained: inline CSS,
JavaScript and data, 8-bit sRGB images beside them, no network access, openable from ``file://``.

Modules: ``_estimate`` (the per-lens depth the page uses), ``_plan`` (which slices, and the
sharpest one per lens), ``_images`` (8-bit images), ``_page`` (the HTML), ``_build`` (a page folder),
``_serve`` (the local server); ``assets/`` holds the page template, its script and style.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ._build import PageOptions, build_page, calibration_summary, camera_summary, page_entry, write_index
from ._estimate import FocusDepth, estimate_depth
from ._picture import build_picture_pages
from ._plan import scene_slices, sharpest_slice
from ._serve import HOST, make_server, serve
