"""Outputs: file names, the linear data products with their metadata, and previews for people.

Data products (contract): each refocused slice and view is one image plus a sidecar ``NAME.json``
with the same fields embedded in the image (:func:`write_slices`, :func:`write_views`,
:func:`write_view_mosaic`). Previews are 8-bit sRGB pictures for looking at — animations, mosaic
previews, the viewer's images — tone-mapped with one documented exposure (:class:`ToneMap`),
enlarged to at least 512 px on the long side (:func:`upscale`) and labelled in metres.

Modules: ``_names`` (file names), ``_optics_tags`` (what the camera's main optics say about the tags: object
space, views at positions or angles, aperture tags), ``_products`` (linear outputs with metadata), ``_tone`` (exposure
and sRGB), ``_display`` (upscaling, labels, metres), ``_previews`` (GIFs and PNG previews),
``_view_set`` (what ``lfproc views`` writes), ``_stack`` (a focal
stack as one ImageJ or OME-TIFF file with its physical spacing; a deconvolved volume and its record), ``_lytro_pictures`` (``lfproc export``: a processed
Lytro picture's stack, depth and views). The depth colour scale lives in :mod:`lfproc.colours` and the 8-bit
picture writers (:func:`write_png_preview`, :func:`write_gif_frames`) in :mod:`lfproc.io`; both are re-exported here. Pillow and
OpenImageIO load only when something is written.

Internal package: not lfproc's API (docs/api.md lists that); its names serve lfproc's own stages, commands and
tests, and may change without notice.
"""

from ..colours import DEPTH_COLOURS, UNKNOWN_COLOUR, colour_scale
from ..io import write_gif_frames, write_png_preview
from ._display import MIN_LONG_SIDE_PX, add_label, metres, slice_label, upscale, upscale_factor
from ._lytro_pictures import export_picture
from ._names import FORMATS, output_stem, slice_names, unique_stems, view_name
from ._optics_tags import stack_f_number
from ._previews import slice_labels, write_mosaic_preview, write_slice_gif, write_slice_previews, write_view_gif
from ._products import slice_metadata, summed_views_metadata, write_slices, write_view_mosaic, write_views
from ._stack import lateral_um_per_lens, stack_path, write_focal_stack, write_volume
from ._tone import ToneMap
from ._view_set import shown_views, write_view_set
