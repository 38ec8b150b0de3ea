"""The camera model: :class:`Camera` (a frozen dataclass of optical parameters) and its camera file.

Private modules: ``_camera`` (the dataclass and derived quantities), ``_main_optics`` (the one interface of
the optics in front of the MLA, :class:`MainOptics`, and the small results its members give), ``_space``
(the unit, origin and direction of object space, :class:`ObjectSpace`), ``_main_lens`` (:class:`MainLens`,
the ``[main_lens]`` table), ``_microscope`` (:class:`Microscope`, the ``[microscope]`` table: objective, tube
lens, relay of a light-field microscope, optionally an objective by its surfaces), ``_transfer`` (the main
optics as a paraxial ray transfer), ``_validation`` (value checks), ``_optics`` (m̂ and b_U closed forms),
``_lens`` (a prescription and its paraxial cardinal points), ``_zmx`` (Zemax ``.zmx`` lens files; glasses from
the ``lfproc[lens]`` extra), ``_toml`` (reading and writing the contract TOML file).
"""

from ._camera import Camera
from ._lens import DEFAULT_LENS_WAVELENGTH_NM, LensPrescription, Surface
from ._main_lens import MainLens
from ._main_optics import MainOptics, UsableRange, ViewPlacement, ViewPupil
from ._microscope import Microscope, WaveOptics
from ._space import NATIVE_PLANE_UM, SENSOR_MM, ObjectSpace, PositionsInSpace, SlicesInSpace
from ._transfer import RayTransfer, main_optics_transfer, prescription_transfer
from ._optics import image_distance_for_focus, largest_odd_at_most
from ._toml import KNOWN_KEYS, parse_provenance
from ._zmx import read_zmx
from ._validation import CFA_PATTERNS, GRIDS, TOML_KEYS

# the public API (docs/api.md); the other names above serve lfproc's own stages and commands
__all__ = ["Camera", "MainOptics", "MainLens", "Microscope", "ObjectSpace"]
