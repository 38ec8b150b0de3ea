"""Forward renderer of Standard Plenoptic Camera raw captures, with exact ground truth.

Scenes (:class:`Scene` of textured :class:`Plane` objects, or a scene file read by
:func:`load_scene_file`, ``docs/scene-format.md``) are rendered through the paper's paraxial optics
by :func:`render` into a raw capture, its white image and the ground truth (:class:`SimulatedCapture`).
Importing this package is light: numba loads on the first render.

Private modules, one concern each: ``_textures`` (plane textures), ``_scene`` (planes and scenes),
``_scene_file`` (TOML scene files), ``_setup`` (lattice, rim and sampling), ``_scene_arrays`` (the scene
as flat arrays), ``_kernels`` (numba ray tracing), ``_render`` (the public render functions),
``_ground_truth`` (what the central view sees), ``_sensor`` (mosaic, noise, DN), ``_checks``
(argument validators), ``_microscope`` (light-field microscope renders: beads and sheets at known depths
through an aplanatic objective, numpy), ``_plane_views`` (exact light fields of a textured plane at a
fractional a: the interpolation-bias ground truth).
"""

from ._microscope import (Bead, MicroscopeScene, Sheet, lens_of_point, render_microscope_capture,
                          render_microscope_sensor,
                          render_microscope_views)
from ._plane_views import fourier_refocus, plane_views
from ._render import SimulatedCapture, render, render_ideal_views, render_radiance, render_white
from ._scene import Plane, Scene
from ._scene_file import RenderOptions, SceneFile, load_scene_file, parse_scene_dict
from ._sensor import LUMA_WEIGHTS, MAX_SHOT_NOISE_PHOTONS, mosaic, radiance_to_dn
from ._setup import aperture_offsets_mm, auto_rim_radius_mm, default_grid, micro_image_scale, pixel_offsets
from ._textures import (KIND_CHECKER, KIND_IMAGE, KIND_NOISE, KIND_SINUSOID, KIND_UNIFORM, TEXTURES, Checkerboard,
                        ImageTexture, Noise, Sinusoid, Uniform, read_texture_image, srgb_to_linear)

# the public API (docs/api.md); the other names above serve lfproc's own stages, commands and benchmarks
__all__ = ["Scene", "Plane", "Noise", "Uniform", "Checkerboard", "Sinusoid", "render", "SimulatedCapture",
           "render_ideal_views", "plane_views", "load_scene_file", "MicroscopeScene", "Bead", "Sheet",
           "render_microscope_sensor", "render_microscope_views"]
