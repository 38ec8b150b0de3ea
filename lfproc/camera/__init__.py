"""The camera model: :class:`Camera` (a frozen dataclass of optical parameters) and its camera file.

Private modules: ``_camera`` (the dataclass and derived quantities), ``_validation`` (value checks),
``_optics`` (m̂ and b_U closed forms), ``_lens`` (a main lens prescription and its
paraxial cardinal points), ``_zmx`` (Zemax ``.zmx`` lens files; glasses from the ``lfproc[lens]`` extra), ``_microscope`` (the ``[microscope]`` table: objective, tube
lens, relay of a light-field microscope), ``_toml`` (reading and writing the contract TOML file).
"""

from ._camera import Camera
from ._lens import DEFAULT_LENS_WAVELENGTH_NM, LensPrescription, Surface
from ._microscope import Microscope
from ._optics import image_distance_for_focus, largest_odd_at_most
from ._toml import KNOWN_KEYS, parse_provenance
from ._zmx import read_zmx
from ._validation import CFA_PATTERNS, GRIDS, TOML_KEYS

__all__ = ["Camera", "LensPrescription", "Surface", "DEFAULT_LENS_WAVELENGTH_NM", "Microscope", "read_zmx", "image_distance_for_focus", "largest_odd_at_most", "KNOWN_KEYS", "parse_provenance",
           "CFA_PATTERNS", "GRIDS", "TOML_KEYS"]
