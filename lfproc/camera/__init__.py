"""The camera model: :class:`Camera` (a frozen dataclass of optical parameters) and its camera file.

Private modules: ``_camera`` (the dataclass and derived quantities), ``_main_optics`` (the one interface of
the optics in front of the MLA, :class:`MainLens` and the unit/origin of object space), ``_transfer`` (the
main optics as a paraxial ray transfer), ``_validation`` (value checks),
``_optics`` (m̂ and b_U closed forms), ``_lens`` (a main lens prescription and its
paraxial cardinal points), ``_zmx`` (Zemax ``.zmx`` lens files; glasses from the ``lfproc[lens]`` extra), ``_microscope`` (the ``[microscope]`` table: objective, tube
lens, relay of a light-field microscope), ``_toml`` (reading and writing the contract TOML file).
"""

from ._camera import Camera
from ._lens import DEFAULT_LENS_WAVELENGTH_NM, LensPrescription, Surface
from ._main_optics import NATIVE_PLANE_UM, SENSOR_MM, MainLens, MainOptics, ObjectSpace, PositionNames, SliceNames
from ._microscope import Microscope, WaveOptics
from ._transfer import RayTransfer, main_optics_transfer, prescription_transfer
from ._optics import image_distance_for_focus, largest_odd_at_most
from ._toml import KNOWN_KEYS, parse_provenance
from ._zmx import read_zmx
from ._validation import CFA_PATTERNS, GRIDS, TOML_KEYS

__all__ = ["Camera", "MainLens", "MainOptics", "ObjectSpace", "PositionNames", "SliceNames", "SENSOR_MM", "NATIVE_PLANE_UM", "RayTransfer",
           "main_optics_transfer", "prescription_transfer", "LensPrescription", "Surface", "DEFAULT_LENS_WAVELENGTH_NM", "Microscope", "WaveOptics", "read_zmx", "image_distance_for_focus", "largest_odd_at_most", "KNOWN_KEYS", "parse_provenance",
           "CFA_PATTERNS", "GRIDS", "TOML_KEYS"]
