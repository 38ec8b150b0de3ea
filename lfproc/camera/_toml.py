"""The camera file (contract TOML, see ARCHITECTURE.md): parsing with one-line errors, and writing.

::

    name
    [sensor]     pixel_pitch_mm, cfa, black_level, white_level
    [mla]        pitch_mm, focal_length_mm, principal_plane_gap_mm, grid
    [main_lens]  focal_length_mm, principal_plane_gap_mm,
                 image_distance_mm | focus_distance_mm, f_number, exit_pupil_distance_mm,
                 prescription (a .zmx file) | [[main_lens.surfaces]], wavelength_nm   (a real lens, _lens.py)
    [microscope] objective_magnification, numerical_aperture, immersion_index, tube_lens_focal_length_mm,
                 relay_magnification, wavelength_nm, aplanatic        (instead of [main_lens]),
                 prescription (a .zmx file) | [[microscope.surfaces]]   (an objective by its surfaces,
                 sample side first, in immersion_index; then M and NA are its own and may be left out)
    [decode]     micro_image_px
    [provenance] "table.key" = "where the value came from"   (optional, issue 11)
"""

from __future__ import annotations

import math
import os

from ..errors import LfprocError
from ..tomlfile import parse_toml, read_toml
from ._lens import DEFAULT_LENS_WAVELENGTH_NM, PRESCRIPTION_TOLERANCE, surfaces_from_table
from ._main_lens import MainLens
from ._microscope import MICROSCOPE_KEYS, Microscope
from ._optics import image_distance_for_focus
from ._validation import require_positive

#: every key a camera file may hold, per table (anything else is a typo and refused)
KNOWN_KEYS = {
    "": {"name", "sensor", "mla", "main_lens", "microscope", "decode", "provenance"},
    "sensor": {"pixel_pitch_mm", "cfa", "black_level", "white_level"},
    "mla": {"pitch_mm", "focal_length_mm", "principal_plane_gap_mm", "grid"},
    "main_lens": {"focal_length_mm", "principal_plane_gap_mm", "image_distance_mm", "focus_distance_mm", "f_number",
                  "exit_pupil_distance_mm", "prescription", "wavelength_nm", "surfaces"},
    "microscope": set(MICROSCOPE_KEYS) | {"prescription", "surfaces"},
    "decode": {"micro_image_px"},
}


def read_camera_file(path: str | os.PathLike) -> dict:
    """The parsed TOML tables of the camera file at ``path`` (errors name the file; napari-LF's metadata and
    Lytro files, which also describe a camera, are told apart and sent to `lfproc.read_camera`)."""
    path = os.fspath(path)
    other = _other_camera_format(path)
    if other is not None:
        raise LfprocError(f"{path}: {other}, not a camera TOML file; `read it with lfproc.read_camera(path), which "
                          f"reads camera files, napari-LF's metadata.txt and Lytro files`")
    return read_toml(path, "camera file", "an existing TOML file to `camera=`")


def _other_camera_format(path: str) -> str | None:
    """What ``path`` is, by its first bytes, when it is one of the other files that describe a camera."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(64)
    except OSError:
        return None                # read_toml says why
    if head.startswith(b"\x89LFP"):
        return "a Lytro file"
    if head.lstrip().startswith(b"{"):
        return "a JSON file (napari-LF's metadata.txt or a Lytro raw's metadata?)"
    return None


def parse_camera_text(text: str, source: str) -> dict:
    """The parsed TOML tables of camera file text (e.g. stored inside a light field file)."""
    return parse_toml(text, source, "camera file")


def camera_fields(data: dict, source: str = "camera") -> dict:
    """Keyword arguments of :class:`Camera` from the parsed tables; every problem raises `LfprocError`."""
    reader = _TableReader(data, source)
    if "main_lens" in data and "microscope" in data:
        raise LfprocError(f"{source}: gives both [main_lens] and [microscope]; keep [microscope] for a light-field "
                          f"microscope, [main_lens] for a camera")
    sensor, mla, decode = (reader.table(t, required=t != "decode") for t in ("sensor", "mla", "decode"))
    if "microscope" not in data and "main_lens" not in data:
        raise LfprocError(f"{source}: missing table [main_lens] (or [microscope] for a light-field microscope); "
                          f"see the camera file format in the README")
    scope = reader.table("microscope") if "microscope" in data else None
    main = reader.table("main_lens") if scope is None else {}
    for table, known in KNOWN_KEYS.items():
        given = data if not table else data.get(table, {})
        unknown = sorted(set(given) - known) if isinstance(given, dict) else []
        if unknown:
            where = f"[{table}]" if table else "the top level"
            raise LfprocError(f"{source}: unknown key {unknown[0]!r} in {where}; the keys there are "
                              f"{', '.join(sorted(known))}")
    f_s = reader.number(mla, "mla", "focal_length_mm")
    mla_gap = reader.number(mla, "mla", "principal_plane_gap_mm", default=0.0)
    optics = _main_lens(reader, main, f_s + mla_gap) if scope is None else _microscope(reader, scope)
    micro = decode.get("micro_image_px") if decode else None
    if micro is not None and (isinstance(micro, bool) or not isinstance(micro, int)):
        if isinstance(micro, float) and micro.is_integer():
            micro = int(micro)
        else:
            raise LfprocError(f"{source}: decode.micro_image_px must be an odd integer, got {micro!r}")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise LfprocError(f"{source}: name must be a string, got {name!r}")
    return dict(
        pixel_pitch_mm=reader.number(sensor, "sensor", "pixel_pitch_mm"),
        mla_pitch_mm=reader.number(mla, "mla", "pitch_mm"),
        mla_focal_length_mm=f_s,
        mla_principal_plane_gap_mm=mla_gap,
        main_optics=optics,
        grid=reader.string(mla, "mla", "grid", "rectangular"),
        cfa=reader.string(sensor, "sensor", "cfa", "none"),
        black_level=reader.number(sensor, "sensor", "black_level", default=0.0),
        white_level=(reader.number(sensor, "sensor", "white_level") if "white_level" in sensor else None),
        micro_image_px=micro,
        name=name,
        provenance=parse_provenance(data.get("provenance", {}), source),
        source=source,
    )


def _prescription(reader: "_TableReader", table: dict, name: str = "main_lens",
                  wavelength: float = DEFAULT_LENS_WAVELENGTH_NM, object_index: float = 1.0):
    """The :class:`LensPrescription` of ``[main_lens]`` (or ``[microscope]``, ``name``): a ``.zmx`` file or the
    inline surfaces, indices at ``wavelength``, ``object_index`` in front of the first surface; or ``None``."""
    source = reader.source
    has_file, has_table = "prescription" in table, "surfaces" in table
    if has_file and has_table:
        raise LfprocError(f"{source}: [{name}] gives both prescription and [[{name}.surfaces]]; keep one")
    if not (has_file or has_table):
        return None
    if has_table:
        return surfaces_from_table(table["surfaces"], source, wavelength, name, object_index)
    file = table["prescription"]
    if not isinstance(file, str) or not file:
        raise LfprocError(f"{source}: {name}.prescription must be a file name (a .zmx lens file), got {file!r}")
    folder = os.path.dirname(os.path.abspath(source)) if os.path.exists(source) else os.getcwd()
    from ._zmx import read_zmx
    return read_zmx(os.path.normpath(os.path.join(folder, os.path.expanduser(file))), wavelength, object_index)


def _agree(reader: "_TableReader", main: dict, key: str, lens_value: float, what: str, table: str = "main_lens") -> None:
    """Refuse a hand-written ``main_lens.key`` (``table``) that differs from the prescription's value by more than
    0.1 %."""
    if key not in main:
        return
    hand = reader.number(main, table, key, allow_inf=True)
    if math.isinf(hand) or math.isinf(lens_value):
        same = hand == lens_value
    else:
        same = abs(hand - lens_value) <= PRESCRIPTION_TOLERANCE * max(abs(lens_value), 1e-3)
    if not same:
        unit = " mm" if table == "main_lens" else ""
        raise LfprocError(f"{reader.source}: {table}.{key} = {hand} disagrees with the prescription's {what} "
                          f"{lens_value:.6g}{unit} (more than 0.1 %); remove it or fix the lens")


def _main_lens(reader: "_TableReader", main: dict, mla_path_mm: float) -> dict:
    """The ``Camera`` fields of a ``[main_lens]`` table; ``mla_path_mm`` = f_s + H1sH2s."""
    source = reader.source
    wavelength = reader.number(main, "main_lens", "wavelength_nm", default=DEFAULT_LENS_WAVELENGTH_NM)
    if not wavelength > 0:
        raise LfprocError(f"{source}: main_lens.wavelength_nm must be positive, got {wavelength}")
    lens = _prescription(reader, main, wavelength=wavelength)
    if lens is None and "wavelength_nm" in main:
        raise LfprocError(f"{source}: main_lens.wavelength_nm needs a prescription (the indices of its glasses); "
                          f"add prescription or [[main_lens.surfaces]], or remove it")
    if lens is None:
        f_u = reader.number(main, "main_lens", "focal_length_mm")
        main_gap = reader.number(main, "main_lens", "principal_plane_gap_mm", default=0.0)
    else:
        f_u, main_gap = lens.focal_length_mm, lens.principal_plane_gap_mm
        _agree(reader, main, "focal_length_mm", f_u, "paraxial focal length")
        _agree(reader, main, "principal_plane_gap_mm", main_gap, "principal plane gap H1U-H2U")
    has_b, has_focus = "image_distance_mm" in main, "focus_distance_mm" in main
    if has_b and has_focus:
        raise LfprocError(f"{source}: [main_lens] gives both image_distance_mm and focus_distance_mm; keep one")
    if not (has_b or has_focus):
        raise LfprocError(f"{source}: [main_lens] needs image_distance_mm or focus_distance_mm; add one")
    if has_b:
        b_u = reader.number(main, "main_lens", "image_distance_mm")
    else:
        focus = reader.number(main, "main_lens", "focus_distance_mm", allow_inf=True)
        require_positive(f_u, "main_lens.focal_length_mm", source)
        b_u = image_distance_for_focus(f_u, focus, mla_path_mm + main_gap, source)
    f_number = main.get("f_number")
    if f_number is not None:
        f_number = reader.number(main, "main_lens", "f_number")
    if lens is None:
        d_a = reader.number(main, "main_lens", "exit_pupil_distance_mm", default=math.inf, allow_inf=True)
    else:
        d_a = lens.exit_pupil_distance_mm(b_u)
        if not d_a > 0:
            raise LfprocError(f"{source}: the prescription's exit pupil lies {-d_a:.3f} mm behind the micro lens "
                              f"array; no plenoptic camera can use that lens there (check b_U and the stop)")
        _agree(reader, main, "exit_pupil_distance_mm", d_a, "exit pupil distance from the MLA")
    return MainLens(f_u, b_u, main_gap, f_number, d_a, lens)


def _microscope(reader: "_TableReader", table: dict) -> Microscope:
    """The ``[microscope]`` table as a :class:`Microscope` (values are checked by ``Microscope.validate``)."""
    def number(key, default=None):
        if default is None and key not in table:
            raise LfprocError(f"{reader.source}: missing microscope.{key}; add it to [microscope]")
        return reader.number(table, "microscope", key, default=default)

    aplanatic = table.get("aplanatic")
    if aplanatic is not None and not isinstance(aplanatic, bool):
        raise LfprocError(f"{reader.source}: microscope.aplanatic must be true or false, got {aplanatic!r}")
    settings = dict(relay_magnification=number("relay_magnification", 1.0),
                    wavelength_nm=number("wavelength_nm") if "wavelength_nm" in table else None, aplanatic=aplanatic)
    index, f_tube = number("immersion_index"), number("tube_lens_focal_length_mm")
    wavelength = 550.0 if settings["wavelength_nm"] is None else settings["wavelength_nm"]
    objective = _prescription(reader, table, "microscope", wavelength, index)
    if objective is None:
        return Microscope(number("objective_magnification"), number("numerical_aperture"), index, f_tube, **settings)
    scope = Microscope.prescribed(objective, f_tube, **settings)   # M and NA from the surfaces
    for key in ("objective_magnification", "numerical_aperture"):
        if key in table:
            _agree(reader, table, key, getattr(scope, key), f"{key.replace('_', ' ')} from its surfaces", "microscope")
    return scope


def parse_provenance(table, source: str) -> tuple[tuple[str, str], ...]:
    """``[provenance]`` as ``((dotted key, text), ...)`` in file order.

    Quoted dotted keys (``"mla.pitch_mm" = "..."``) and TOML's nested form (``mla.pitch_mm = "..."``,
    which parses into sub-tables) both give the key ``"mla.pitch_mm"``.
    """
    if not isinstance(table, dict):
        raise LfprocError(f"{source}: 'provenance' must be a table [provenance] of \"key\" = \"text\" lines")
    pairs = []

    def walk(node, prefix):
        for key, value in node.items():
            dotted = f"{prefix}{key}"
            if isinstance(value, dict):
                walk(value, dotted + ".")
            elif isinstance(value, str):
                pairs.append((dotted, value))
            else:
                raise LfprocError(f"{source}: provenance of {dotted!r} must be a string, got {value!r}; "
                                  f"write \"{dotted}\" = \"where it came from\"")

    walk(table, "")
    return tuple(pairs)


def camera_to_toml(camera, include_provenance: bool = True) -> str:
    """The camera as a contract TOML file (b_U written as ``image_distance_mm``; full precision). ``[decode]
    micro_image_px`` is written where the camera states m̂ (`Camera.micro_image_px_given`); an m̂ derived from the
    nominal pitch is left out (a comment says so), so that the file read back leaves m̂ to the measured pitch too."""
    lines = []
    if camera.name:
        lines.append(f"name = {_toml_str(camera.name)}")
    lines += ["[sensor]", f"pixel_pitch_mm = {camera.pixel_pitch_mm!r}", f"cfa = {_toml_str(camera.cfa)}",
              f"black_level = {float(camera.black_level)!r}"]
    if camera.white_level is not None:
        lines.append(f"white_level = {float(camera.white_level)!r}")
    lines += ["[mla]", f"pitch_mm = {camera.mla_pitch_mm!r}", f"focal_length_mm = {camera.mla_focal_length_mm!r}",
              f"principal_plane_gap_mm = {camera.mla_principal_plane_gap_mm!r}", f"grid = {_toml_str(camera.grid)}"]
    lines += camera.main_optics.toml_lines()
    lines.append("[decode]")
    if camera.micro_image_px_given:
        lines.append(f"micro_image_px = {camera.m_hat}")
    else:     # left to the measurement: decoding with a white image or grid takes m̂ from the measured pitch
        lines.append(f"# micro_image_px not stated: the largest odd integer not above the measured micro image pitch "
                     f"when decoded with a white image or grid, else {camera.m_hat} from the nominal "
                     f"{camera.pitch_px:.3f} px")
    if include_provenance and camera.provenance:
        lines.append("[provenance]")
        lines += [f"{_toml_str(key)} = {_toml_str(text)}" for key, text in camera.provenance]
    return "\n".join(lines) + "\n"


class _TableReader:
    """Typed access to the parsed TOML with messages that name the file, table and key."""

    def __init__(self, data: dict, source: str):
        self.data, self.source = data, source

    def table(self, name: str, required: bool = True) -> dict:
        value = self.data.get(name)
        if value is None:
            if required:
                raise LfprocError(f"{self.source}: missing table [{name}]; see the camera file format in the README")
            return {}
        if not isinstance(value, dict):
            raise LfprocError(f"{self.source}: '{name}' must be a table [{name}], got {type(value).__name__}")
        return value

    def number(self, table: dict, tname: str, key: str, default=None, allow_inf: bool = False) -> float:
        if key not in table:
            if default is not None:
                return float(default)
            raise LfprocError(f"{self.source}: missing {tname}.{key}; add it to [{tname}] (millimetres)")
        value = table[key]
        if isinstance(value, str) and allow_inf and value.strip().lower() in ("inf", "infinity"):
            return math.inf
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise LfprocError(f"{self.source}: {tname}.{key} must be a number, got {value!r}")
        value = float(value)
        if math.isnan(value) or (math.isinf(value) and not allow_inf):
            raise LfprocError(f"{self.source}: {tname}.{key} must be finite, got {value}")
        return value

    def string(self, table: dict, tname: str, key: str, default: str) -> str:
        value = table.get(key, default)
        if not isinstance(value, str):
            raise LfprocError(f"{self.source}: {tname}.{key} must be a string, got {value!r}")
        return value


def _toml_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
