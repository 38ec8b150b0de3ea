"""Scene files (TOML, ``docs/scene-format.md``): a camera, a scene and the render options; for a microscope camera,
fluorescent beads (``[[bead]]``) instead of planes.

:func:`load_scene_file` parses one into a :class:`SceneFile`; every problem raises
:class:`lfproc.LfprocError` naming the file, the table and the key.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, fields

from ..camera import Camera
from ..errors import LfprocError
from ..tomlfile import read_toml
from ._checks import _integer, _number, _number_list
from ._microscope import Bead
from ._scene import Plane, Scene
from ._textures import Checkerboard, ImageTexture, Noise, Sinusoid, Uniform, read_texture_image


@dataclass(frozen=True)
class RenderOptions:
    """The ``[render]`` table of a scene file: the keyword arguments of :func:`lfproc.simulate.render`."""

    height_px: int = 480
    width_px: int = 640
    rotation_deg: float = 0.0
    offset_px: tuple = (0.0, 0.0)
    rim_radius_mm: object = "auto"
    pixel_samples: int = 2
    aperture_samples: int = 3
    shot_noise_photons: float | None = None
    read_noise_dn: float = 0.0
    exposure: float = 0.8
    seed: int = 0
    ideal_views: bool = True
    exit_pupil_distance_mm: float | None = None  # None: the camera's

    @property
    def sensor_shape(self) -> tuple[int, int]:
        return (self.height_px, self.width_px)

    def render_kwargs(self) -> dict:
        """Keyword arguments for :func:`lfproc.simulate.render` (sensor shape excluded)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("height_px", "width_px")}

    def to_json_dict(self) -> dict:
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["offset_px"] = list(self.offset_px)
        if isinstance(self.rim_radius_mm, float) and math.isinf(self.rim_radius_mm):
            out["rim_radius_mm"] = None
        if self.exit_pupil_distance_mm is None:
            del out["exit_pupil_distance_mm"]  # the camera's (and the format of files written before the key)
        elif math.isinf(self.exit_pupil_distance_mm):
            out["exit_pupil_distance_mm"] = "inf"  # JSON has no infinity
        return out


@dataclass(frozen=True, eq=False)
class SceneFile:
    """A parsed scene file: the camera, the scene and the render options."""

    camera: Camera
    scene: Scene
    options: RenderOptions
    source: str = field(default="", compare=False)
    beads: tuple = ()       # a microscope's fluorescent beads (Bead), rendered instead of the planes


_PLANE_COMMON = {"name", "distance_mm", "texture", "region_mm", "tint", "center_mm", "tilt_deg"}
_TEXTURE_KEYS = {
    "uniform": {"value"},
    "checkerboard": {"period_mm", "low", "high"},
    "sinusoid": {"period_mm", "angle_deg", "phase_deg", "low", "high"},
    "grating": {"period_mm", "angle_deg", "phase_deg", "low", "high"},
    "noise": {"feature_mm", "seed", "low", "high"},
    "image": {"path", "width_mm", "encoding", "low", "high"},
}
_TOP_KEYS = {"camera", "background", "render", "plane", "bead"}
_BEAD_KEYS = {"x_um", "y_um", "z_um", "radius_um", "brightness"}


def load_scene_file(path: str | os.PathLike) -> SceneFile:
    """Parse a scene TOML file (``docs/scene-format.md``); every problem raises `LfprocError` naming the file.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    SceneFile
        The scene, the camera file it names and the render options.
    """
    path = os.fspath(path)
    data = read_toml(path, "scene file", "an existing SCENE.toml")
    return parse_scene_dict(data, source=path, base_dir=os.path.dirname(os.path.abspath(path)))


def parse_scene_dict(data: dict, source: str = "scene", base_dir: str = ".") -> SceneFile:
    """Build a :class:`SceneFile` from parsed TOML; relative paths resolve against ``base_dir``."""
    unknown = set(data) - _TOP_KEYS
    if unknown:
        raise LfprocError(f"{source}: unknown top-level key(s) {sorted(unknown)}; expected camera, background, "
                          f"[render] and [[plane]]")
    camera = _parse_camera(data.get("camera"), source, base_dir)
    background = data.get("background", 0.0)
    if isinstance(background, (int, float)) and not isinstance(background, bool):
        background = [background] * 3
    background = _number_list(background, 3, f"{source}: background")
    options = _parse_render(data.get("render", {}), source)
    plane_tables = data.get("plane", [])
    if not isinstance(plane_tables, list):
        raise LfprocError(f"{source}: 'plane' must be an array of tables [[plane]]")
    planes = tuple(_parse_plane(t, k, source, base_dir) for k, t in enumerate(plane_tables))
    beads = _parse_beads(data.get("bead", []), planes, camera, source)
    try:
        scene = Scene(planes=planes, background=tuple(background))
    except LfprocError as exc:
        raise LfprocError(f"{source}: {exc.marked}") from None
    return SceneFile(camera=camera, scene=scene, options=options, source=source, beads=beads)


def _parse_beads(tables, planes, camera: Camera, source: str) -> tuple:
    """The ``[[bead]]`` tables: fluorescent beads at (x_um, y_um, z_um) in a microscope's sample."""
    from ..camera import Microscope

    if not isinstance(tables, list):
        raise LfprocError(f"{source}: 'bead' must be an array of tables [[bead]]")
    if tables and not isinstance(camera.main_optics, Microscope):
        raise LfprocError(f"{source}: [[bead]] needs a microscope camera (a [microscope] table); this camera has "
                          f"a main lens: give [[plane]]s instead")
    if tables and planes:
        raise LfprocError(f"{source}: a scene has [[plane]]s (a camera) or [[bead]]s (a microscope), not both")
    beads = []
    for index, table in enumerate(tables):
        where = f"{source} [[bead]] #{index + 1}"
        if not isinstance(table, dict):
            raise LfprocError(f"{where}: must be a table")
        unknown, missing = set(table) - _BEAD_KEYS, {"x_um", "y_um", "z_um"} - set(table)
        if unknown or missing:
            raise LfprocError(f"{where}: {'unknown key(s) ' + str(sorted(unknown)) if unknown else ''}"
                              f"{'; ' if unknown and missing else ''}"
                              f"{'missing ' + ', '.join(sorted(missing)) if missing else ''}; keys: x_um, y_um, "
                              f"z_um (µm in the sample, z from the native object plane), radius_um, brightness")
        try:
            beads.append(Bead(**table))
        except (LfprocError, TypeError) as exc:
            raise LfprocError(f"{where}: {exc}") from None
    return tuple(beads)


def _parse_camera(value, source: str, base_dir: str) -> Camera:
    if value is None:
        raise LfprocError(f"{source}: missing 'camera'; give camera = \"path/to/camera.toml\" or a [camera] table")
    if isinstance(value, str):
        cam_path = value if os.path.isabs(value) else os.path.join(base_dir, value)
        return Camera.from_toml(cam_path)
    if isinstance(value, dict):
        return Camera.from_dict(value, source=f"{source} [camera]")
    raise LfprocError(f"{source}: 'camera' must be a path string or a table, got {type(value).__name__}")


def _parse_render(table, source: str) -> RenderOptions:
    where = f"{source} [render]"
    if not isinstance(table, dict):
        raise LfprocError(f"{source}: 'render' must be a table [render]")
    known = {f.name for f in fields(RenderOptions)}
    unknown = set(table) - known
    if unknown:
        raise LfprocError(f"{where}: unknown key(s) {sorted(unknown)}; known keys: {', '.join(sorted(known))}")
    kw = {}
    for key in ("height_px", "width_px", "pixel_samples", "aperture_samples", "seed"):
        if key in table:
            kw[key] = _integer(table[key], f"{where}: {key}", minimum=0 if key == "seed" else 1)
    for key in ("rotation_deg", "read_noise_dn", "exposure"):
        if key in table:
            kw[key] = _number(table[key], f"{where}: {key}")
    if "offset_px" in table:
        kw["offset_px"] = tuple(_number_list(table["offset_px"], 2, f"{where}: offset_px"))
    if "rim_radius_mm" in table:
        rim = table["rim_radius_mm"]
        if isinstance(rim, str) and rim.strip().lower() in ("auto", "none", "off", "inf"):
            rim = rim.strip().lower()
            kw["rim_radius_mm"] = "auto" if rim == "auto" else None
        elif rim is False:
            kw["rim_radius_mm"] = None
        else:
            kw["rim_radius_mm"] = _number(rim, f"{where}: rim_radius_mm (a number, \"auto\" or \"none\")")
    if "shot_noise_photons" in table:
        photons = table["shot_noise_photons"]
        # `photons in (False, ...)` would also match 0 (0 == False): only the literal false turns noise off
        off = photons is False or (isinstance(photons, str) and photons in ("none", "off"))
        kw["shot_noise_photons"] = None if off else _number(photons, f"{where}: shot_noise_photons")
        if not off and kw["shot_noise_photons"] <= 0:
            raise LfprocError(f"{where}: shot_noise_photons must be a positive number of photons at full scale, "
                              f"or \"none\", got {photons!r}")
    if "ideal_views" in table:
        if not isinstance(table["ideal_views"], bool):
            raise LfprocError(f"{where}: ideal_views must be true or false")
        kw["ideal_views"] = table["ideal_views"]
    if "exit_pupil_distance_mm" in table:
        kw["exit_pupil_distance_mm"] = _parse_exit_pupil(table["exit_pupil_distance_mm"], where)
    return RenderOptions(**kw)


def _parse_exit_pupil(value, where: str) -> float | None:
    """A positive distance in mm, inf (or "inf": telecentric), or "camera" (None: the camera file's value)."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "camera"):
        return math.inf if value.strip().lower() == "inf" else None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value) or value <= 0:
        raise LfprocError(f"{where}: exit_pupil_distance_mm must be a positive distance in mm, inf (telecentric) "
                          f"or \"camera\", got {value!r}")
    return float(value)


def _parse_plane(table, index: int, source: str, base_dir: str) -> Plane:
    where = f"{source} [[plane]] #{index + 1}"
    if not isinstance(table, dict):
        raise LfprocError(f"{where}: must be a table")
    if "name" in table:
        if not isinstance(table["name"], str):
            raise LfprocError(f"{where}: name must be a string")
        where = f"{source} [[plane]] {table['name']!r}"
    kind = table.get("texture")
    if not isinstance(kind, str) or kind not in _TEXTURE_KEYS:
        raise LfprocError(f"{where}: texture must be one of {', '.join(sorted(_TEXTURE_KEYS))}, got {kind!r}")
    unknown = set(table) - _PLANE_COMMON - _TEXTURE_KEYS[kind]
    if unknown:
        raise LfprocError(f"{where}: unknown key(s) {sorted(unknown)} for texture {kind!r}; allowed: "
                          f"{', '.join(sorted(_PLANE_COMMON | _TEXTURE_KEYS[kind]))}")
    if "distance_mm" not in table:
        raise LfprocError(f"{where}: missing distance_mm (distance from the sensor, mm)")
    try:
        texture = _parse_texture(kind, table, where, base_dir)
        return Plane(distance_mm=_number(table["distance_mm"], f"{where}: distance_mm"), texture=texture,
                     region_mm=(None if "region_mm" not in table else
                                tuple(_number_list(table["region_mm"], 4, f"{where}: region_mm"))),
                     tint=tuple(_number_list(table.get("tint", [1.0, 1.0, 1.0]), 3, f"{where}: tint")),
                     center_mm=tuple(_number_list(table.get("center_mm", [0.0, 0.0]), 2, f"{where}: center_mm")),
                     name=table.get("name", ""),
                     tilt_deg=tuple(_number_list(table.get("tilt_deg", [0.0, 0.0]), 2, f"{where}: tilt_deg")))
    except LfprocError as exc:
        msg = str(exc)
        raise LfprocError(msg if msg.startswith(source) else f"{where}: {msg}") from None


def _parse_texture(kind: str, table: dict, where: str, base_dir: str):
    def num(key, default=None):
        if key not in table:
            if default is None:
                raise LfprocError(f"{where}: texture {kind!r} needs {key}")
            return default
        return _number(table[key], f"{where}: {key}")

    if kind == "uniform":
        return Uniform(value=num("value", 1.0))
    levels = dict(low=num("low", 0.0), high=num("high", 1.0))
    if kind == "checkerboard":
        return Checkerboard(period_mm=num("period_mm"), **levels)
    if kind in ("sinusoid", "grating"):
        return Sinusoid(period_mm=num("period_mm"), angle_deg=num("angle_deg", 0.0),
                        phase_deg=num("phase_deg", 0.0), **levels)
    if kind == "noise":
        return Noise(feature_mm=num("feature_mm"), seed=_integer(table.get("seed", 0), f"{where}: seed", 0),
                     **levels)
    path = table.get("path")
    if not isinstance(path, str) or not path:
        raise LfprocError(f"{where}: texture 'image' needs path = \"picture.png\" (relative to the scene file)")
    encoding = table.get("encoding", "srgb")
    if encoding not in ("srgb", "linear"):
        raise LfprocError(f"{where}: encoding must be \"srgb\" or \"linear\", got {encoding!r}")
    full = path if os.path.isabs(path) else os.path.join(base_dir, path)
    return ImageTexture(pixels=read_texture_image(full, encoding), width_mm=num("width_mm"), source=path, **levels)
