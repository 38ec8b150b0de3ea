"""The camera file (contract TOML, see ARCHITECTURE.md): parsing with one-line errors, and writing.

::

    name
    [sensor]     pixel_pitch_mm, cfa, black_level, white_level
    [mla]        pitch_mm, focal_length_mm, principal_plane_gap_mm, grid
    [main_lens]  focal_length_mm, principal_plane_gap_mm,
                 image_distance_mm | focus_distance_mm, f_number, exit_pupil_distance_mm
    [decode]     micro_image_px
    [provenance] "table.key" = "where the value came from"   (optional, issue 11)
"""

from __future__ import annotations

import math
import os

from ..errors import LfprocError
from ..tomlfile import parse_toml, read_toml
from ._optics import image_distance_for_focus
from ._validation import require_positive

#: every key a camera file may hold, per table (anything else is a typo and refused)
KNOWN_KEYS = {
    "": {"name", "sensor", "mla", "main_lens", "decode", "provenance"},
    "sensor": {"pixel_pitch_mm", "cfa", "black_level", "white_level"},
    "mla": {"pitch_mm", "focal_length_mm", "principal_plane_gap_mm", "grid"},
    "main_lens": {"focal_length_mm", "principal_plane_gap_mm", "image_distance_mm", "focus_distance_mm", "f_number",
                  "exit_pupil_distance_mm"},
    "decode": {"micro_image_px"},
}


def read_camera_file(path: str | os.PathLike) -> dict:
    """The parsed TOML tables of the camera file at ``path`` (errors name the file)."""
    return read_toml(os.fspath(path), "camera file", "an existing TOML file to --camera")


def parse_camera_text(text: str, source: str) -> dict:
    """The parsed TOML tables of camera file text (e.g. stored inside a light field file)."""
    return parse_toml(text, source, "camera file")


def camera_fields(data: dict, source: str = "camera") -> dict:
    """Keyword arguments of :class:`Camera` from the parsed tables; every problem raises `LfprocError`."""
    reader = _TableReader(data, source)
    sensor, mla, main, decode = (reader.table(t, required=t != "decode") for t in
                                 ("sensor", "mla", "main_lens", "decode"))
    for table, known in KNOWN_KEYS.items():
        given = data if not table else data.get(table, {})
        unknown = sorted(set(given) - known) if isinstance(given, dict) else []
        if unknown:
            where = f"[{table}]" if table else "the top level"
            raise LfprocError(f"{source}: unknown key {unknown[0]!r} in {where}; the keys there are "
                              f"{', '.join(sorted(known))}")
    f_u = reader.number(main, "main_lens", "focal_length_mm")
    main_gap = reader.number(main, "main_lens", "principal_plane_gap_mm", default=0.0)
    f_s = reader.number(mla, "mla", "focal_length_mm")
    mla_gap = reader.number(mla, "mla", "principal_plane_gap_mm", default=0.0)
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
        b_u = image_distance_for_focus(f_u, focus, f_s + mla_gap + main_gap, source)
    micro = decode.get("micro_image_px") if decode else None
    if micro is not None and (isinstance(micro, bool) or not isinstance(micro, int)):
        if isinstance(micro, float) and micro.is_integer():
            micro = int(micro)
        else:
            raise LfprocError(f"{source}: decode.micro_image_px must be an odd integer, got {micro!r}")
    f_number = main.get("f_number")
    if f_number is not None:
        f_number = reader.number(main, "main_lens", "f_number")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise LfprocError(f"{source}: name must be a string, got {name!r}")
    return dict(
        pixel_pitch_mm=reader.number(sensor, "sensor", "pixel_pitch_mm"),
        mla_pitch_mm=reader.number(mla, "mla", "pitch_mm"),
        mla_focal_length_mm=f_s,
        main_focal_length_mm=f_u,
        image_distance_mm=b_u,
        mla_principal_plane_gap_mm=mla_gap,
        main_principal_plane_gap_mm=main_gap,
        f_number=f_number,
        grid=reader.string(mla, "mla", "grid", "rectangular"),
        cfa=reader.string(sensor, "sensor", "cfa", "none"),
        black_level=reader.number(sensor, "sensor", "black_level", default=0.0),
        white_level=(reader.number(sensor, "sensor", "white_level") if "white_level" in sensor else None),
        exit_pupil_distance_mm=reader.number(main, "main_lens", "exit_pupil_distance_mm", default=math.inf,
                                             allow_inf=True),
        micro_image_px=micro,
        name=name,
        provenance=parse_provenance(data.get("provenance", {}), source),
        source=source,
    )


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
    """The camera as a contract TOML file (b_U written as ``image_distance_mm``; full precision)."""
    lines = []
    if camera.name:
        lines.append(f"name = {_toml_str(camera.name)}")
    lines += ["[sensor]", f"pixel_pitch_mm = {camera.pixel_pitch_mm!r}", f"cfa = {_toml_str(camera.cfa)}",
              f"black_level = {float(camera.black_level)!r}"]
    if camera.white_level is not None:
        lines.append(f"white_level = {float(camera.white_level)!r}")
    lines += ["[mla]", f"pitch_mm = {camera.mla_pitch_mm!r}", f"focal_length_mm = {camera.mla_focal_length_mm!r}",
              f"principal_plane_gap_mm = {camera.mla_principal_plane_gap_mm!r}", f"grid = {_toml_str(camera.grid)}",
              "[main_lens]", f"focal_length_mm = {camera.main_focal_length_mm!r}",
              f"principal_plane_gap_mm = {camera.main_principal_plane_gap_mm!r}",
              f"image_distance_mm = {camera.image_distance_mm!r}"]
    if camera.f_number is not None:
        lines.append(f"f_number = {camera.f_number!r}")
    if not camera.telecentric:
        lines.append(f"exit_pupil_distance_mm = {camera.exit_pupil_distance_mm!r}")
    lines += ["[decode]", f"micro_image_px = {camera.m_hat}"]
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
