"""Synthetic scenes for the simulator (compatibility path): the names live in :mod:`lfproc.simulate`.

``from lfproc.scene import Plane, Scene, Noise, load_scene_file, ...`` keeps working; new code may
import the same names from ``lfproc.simulate``.
"""

from .simulate import (KIND_CHECKER, KIND_IMAGE, KIND_NOISE, KIND_SINUSOID, KIND_UNIFORM, TEXTURES,
                       Checkerboard, ImageTexture, Noise, Plane, RenderOptions, Scene, SceneFile, Sinusoid,
                       Uniform, load_scene_file, parse_scene_dict, read_texture_image, srgb_to_linear)

__all__ = [
                       "KIND_CHECKER",
                       "KIND_IMAGE",
                       "KIND_NOISE",
                       "KIND_SINUSOID",
                       "KIND_UNIFORM",
                       "TEXTURES",
                       "Checkerboard",
                       "ImageTexture",
                       "Noise",
                       "Plane",
                       "RenderOptions",
                       "Scene",
                       "SceneFile",
                       "Sinusoid",
                       "Uniform",
                       "load_scene_file",
                       "parse_scene_dict",
                       "read_texture_image",
                       "srgb_to_linear",
]
