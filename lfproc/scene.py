"""Synthetic scenes for the simulator: fronto-parallel textured planes, and the scene file that names them.

A :class:`Scene` is a tuple of :class:`Plane` objects plus a background radiance. Each plane sits at
``distance_mm`` from the sensor (the paper's distance convention, Eq. 21), carries one texture, an
optional rectangular region and an RGB tint. A ray takes the radiance of the nearest plane whose
region it hits, otherwise the background.

Plane coordinates
-----------------
``(x, y)`` in mm on the plane, the optical axis at ``(0, 0)``, oriented *as seen in the capture*:
x grows with the sensor column and y with the sensor row of the upright picture that refocusing
and viewpoint extraction produce. (The optics invert the picture on the sensor; the renderer
accounts for that, so an image texture appears upright in the decoded views.)

Textures (value ``t`` in [0, 1], mapped to ``low + (high − low)·t`` and multiplied by the tint):

* :class:`Uniform` — a constant ``value``;
* :class:`Checkerboard` — squares of side ``period_mm / 2`` (one period = two squares);
* :class:`Sinusoid` — ``½ + ½·cos(2π·(x cos θ + y sin θ)/period + φ)``, a grating at angle θ;
* :class:`Noise` — band-limited value noise: random values on a lattice of spacing ``feature_mm``
  (plus half as much at half the spacing), blended with a C² quintic, deterministic for a ``seed``;
* :class:`ImageTexture` — an image file mapped onto ``width_mm`` (height from its aspect ratio),
  centred on ``center_mm``, sampled bilinearly; outside the image the plane is not there.

The scene file format (TOML) is documented in ``docs/scene-format.md``; :func:`load_scene_file`
parses it into a camera, a scene and :class:`RenderOptions`.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, fields

import numpy as np

from .camera import Camera
from .errors import LfprocError
from .tomlfile import read_toml


#: texture kind ids shared with the numba kernels of :mod:`lfproc.simulate`
KIND_UNIFORM, KIND_CHECKER, KIND_SINUSOID, KIND_NOISE, KIND_IMAGE = range(5)


# ---------------------------------------------------------------------------- textures
class _LowHigh:
    """Textures whose value t in [0, 1] maps to ``low + (high − low)·t``."""

    def levels(self) -> tuple[float, float]:
        return float(self.low), float(self.high)


@dataclass(frozen=True)
class Uniform:
    """A constant radiance ``value``."""

    value: float = 1.0
    kind = KIND_UNIFORM

    def __post_init__(self):
        _check_level(self.value, "value")

    def levels(self) -> tuple[float, float]:
        return float(self.value), float(self.value)


@dataclass(frozen=True)
class Checkerboard(_LowHigh):
    """Checkerboard of period ``period_mm`` (squares of side ``period_mm / 2``): the square
    0 ≤ x, y < period/2 (lower-right of the origin, since y grows downward) is ``low``."""

    period_mm: float
    low: float = 0.0
    high: float = 1.0
    kind = KIND_CHECKER

    def __post_init__(self):
        _check_positive(self.period_mm, "period_mm")
        _check_levels(self.low, self.high)


@dataclass(frozen=True)
class Sinusoid(_LowHigh):
    """Sinusoidal grating of period ``period_mm`` whose stripes run across the direction ``angle_deg``
    (from +x towards +y); ``phase_deg`` shifts it."""

    period_mm: float
    angle_deg: float = 0.0
    phase_deg: float = 0.0
    low: float = 0.0
    high: float = 1.0
    kind = KIND_SINUSOID

    def __post_init__(self):
        _check_positive(self.period_mm, "period_mm")
        _check_finite(self.angle_deg, "angle_deg")
        _check_finite(self.phase_deg, "phase_deg")
        _check_levels(self.low, self.high)


@dataclass(frozen=True)
class Noise(_LowHigh):
    """Band-limited random texture: value noise with lattice spacing ``feature_mm`` (see the module docstring)."""

    feature_mm: float
    seed: int = 0
    low: float = 0.0
    high: float = 1.0
    kind = KIND_NOISE

    def __post_init__(self):
        _check_positive(self.feature_mm, "feature_mm")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or not 0 <= self.seed < 2**31:
            raise LfprocError(f"noise seed must be an integer in [0, 2^31), got {self.seed!r}")
        _check_levels(self.low, self.high)


@dataclass(frozen=True, eq=False)
class ImageTexture(_LowHigh):
    """An RGB image (``pixels`` shaped (h, w, 3), linear float in [0, 1]) mapped onto ``width_mm``.

    Row 0 of the image is at the smallest y (top of the upright picture), column 0 at the smallest x.
    """

    pixels: np.ndarray
    width_mm: float
    low: float = 0.0
    high: float = 1.0
    source: str = ""
    kind = KIND_IMAGE

    def __post_init__(self):
        _check_positive(self.width_mm, "width_mm")
        _check_levels(self.low, self.high)
        px = np.asarray(self.pixels)
        if px.ndim != 3 or px.shape[2] != 3 or px.shape[0] < 1 or px.shape[1] < 1:
            raise LfprocError(f"image texture {self.source or ''} must be shaped (h, w, 3), got {px.shape}")
        if not np.all(np.isfinite(px)):
            raise LfprocError(f"image texture {self.source or ''} holds NaN or infinite values; fix the image")
        object.__setattr__(self, "pixels", np.ascontiguousarray(px, dtype=np.float32))

    @property
    def height_mm(self) -> float:
        h, w = self.pixels.shape[:2]
        return self.width_mm * h / w


TEXTURES = {"uniform": Uniform, "checkerboard": Checkerboard, "sinusoid": Sinusoid, "grating": Sinusoid,
            "noise": Noise, "image": ImageTexture}


# ---------------------------------------------------------------------------- planes and scenes
@dataclass(frozen=True)
class Plane:
    """A fronto-parallel textured plane.

    Parameters
    ----------
    distance_mm : float
        Distance from the sensor (like every distance in lfproc; Eq. 21).
    texture : Uniform, Checkerboard, Sinusoid, Noise or ImageTexture
    region_mm : (x0, x1, y0, y1) or None
        The part of the plane that exists, in plane coordinates (mm, optical axis at 0); ``None`` is
        unbounded (an image texture is always bounded by the image).
    tint : (r, g, b)
        Multiplies the texture value per channel.
    center_mm : (x, y)
        Where the texture's origin (an image's centre) lies on the plane.
    name : str
    """

    distance_mm: float
    texture: object
    region_mm: tuple | None = None
    tint: tuple = (1.0, 1.0, 1.0)
    center_mm: tuple = (0.0, 0.0)
    name: str = ""

    def __post_init__(self):
        where = f"plane {self.name!r}" if self.name else "plane"
        d = self.distance_mm
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not math.isfinite(d) or d <= 0:
            raise LfprocError(f"{where}: distance_mm must be a finite positive distance from the sensor, got {d!r}")
        if not isinstance(self.texture, tuple(set(TEXTURES.values()))):
            raise LfprocError(f"{where}: texture must be one of {', '.join(sorted(TEXTURES))}")
        if self.region_mm is not None:
            region = _float_tuple(self.region_mm, 4, f"{where}: region_mm")
            if not (region[0] < region[1] and region[2] < region[3]):
                raise LfprocError(f"{where}: region_mm = {list(region)} must be [x0, x1, y0, y1] with x0 < x1 and "
                                  f"y0 < y1")
            object.__setattr__(self, "region_mm", region)
        tint = _float_tuple(self.tint, 3, f"{where}: tint")
        if min(tint) < 0:
            raise LfprocError(f"{where}: tint {list(tint)} must not be negative")
        object.__setattr__(self, "tint", tint)
        object.__setattr__(self, "center_mm", _float_tuple(self.center_mm, 2, f"{where}: center_mm"))

    def describe(self) -> dict:
        """A JSON-ready description (the image pixels are replaced by their source path)."""
        tex = self.texture
        kind = next(name for name, cls in TEXTURES.items() if isinstance(tex, cls))
        params = {f.name: getattr(tex, f.name) for f in fields(tex) if f.name not in ("pixels",)}
        return {"name": self.name, "distance_mm": float(self.distance_mm), "texture": kind, **params,
                "region_mm": None if self.region_mm is None else list(self.region_mm),
                "tint": list(self.tint), "center_mm": list(self.center_mm)}


@dataclass(frozen=True)
class Scene:
    """Planes (in the order given; ties in distance go to the earlier plane) and a background radiance (RGB)."""

    planes: tuple = ()
    background: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        planes = tuple(self.planes)
        for p in planes:
            if not isinstance(p, Plane):
                raise LfprocError(f"scene planes must be Plane objects, got {type(p).__name__}")
        object.__setattr__(self, "planes", planes)
        bg = self.background
        bg = (bg, bg, bg) if isinstance(bg, (int, float)) and not isinstance(bg, bool) else bg
        bg = _float_tuple(bg, 3, "scene background")
        if min(bg) < 0:
            raise LfprocError(f"scene background {list(bg)} must not be negative")
        object.__setattr__(self, "background", bg)


# ---------------------------------------------------------------------------- render options
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
        return out


@dataclass(frozen=True, eq=False)
class SceneFile:
    """A parsed scene file: the camera, the scene and the render options."""

    camera: Camera
    scene: Scene
    options: RenderOptions
    source: str = field(default="", compare=False)


_PLANE_COMMON = {"name", "distance_mm", "texture", "region_mm", "tint", "center_mm"}
_TEXTURE_KEYS = {
    "uniform": {"value"},
    "checkerboard": {"period_mm", "low", "high"},
    "sinusoid": {"period_mm", "angle_deg", "phase_deg", "low", "high"},
    "grating": {"period_mm", "angle_deg", "phase_deg", "low", "high"},
    "noise": {"feature_mm", "seed", "low", "high"},
    "image": {"path", "width_mm", "encoding", "low", "high"},
}
_TOP_KEYS = {"camera", "background", "render", "plane"}


def load_scene_file(path: str | os.PathLike) -> SceneFile:
    """Parse a scene TOML file (``docs/scene-format.md``); every problem raises `LfprocError` naming the file."""
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
    try:
        scene = Scene(planes=planes, background=tuple(background))
    except LfprocError as exc:
        raise LfprocError(f"{source}: {exc}") from None
    return SceneFile(camera=camera, scene=scene, options=options, source=source)


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
    return RenderOptions(**kw)


def _parse_plane(table, index: int, source: str, base_dir: str) -> Plane:
    where = f"{source} [[plane]] #{index + 1}"
    if not isinstance(table, dict):
        raise LfprocError(f"{where}: must be a table")
    if "name" in table:
        if not isinstance(table["name"], str):
            raise LfprocError(f"{where}: name must be a string")
        where = f"{source} [[plane]] {table['name']!r}"
    kind = table.get("texture")
    if kind not in _TEXTURE_KEYS:
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
                     name=table.get("name", ""))
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


def read_texture_image(path: str, encoding: str = "srgb") -> np.ndarray:
    """Read an image file as linear RGB float32 (h, w, 3) >= 0, through :func:`lfproc.io.read_image`.

    Integer files are scaled to [0, 1] (divided by their type's maximum); float files keep their
    values, so a linear EXR may exceed 1. ``encoding="srgb"`` clips to [0, 1] and undoes the sRGB
    transfer curve. Grey (and grey + alpha) images are replicated to three channels; channels after
    the third (alpha) are dropped.
    """
    from .io import read_image

    if not os.path.isfile(path):
        raise LfprocError(f"{path}: texture image not found; check the plane's path (relative to the scene file)")
    pixels = read_image(path)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    channels = pixels.shape[2]
    if channels in (1, 2):
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    else:
        pixels = pixels[:, :, :3]
    pixels = np.clip(np.nan_to_num(pixels, nan=0.0, posinf=1.0, neginf=0.0), 0.0, None)
    if encoding == "srgb":
        pixels = srgb_to_linear(np.clip(pixels, 0.0, 1.0))
    return np.ascontiguousarray(pixels, dtype=np.float32)


def srgb_to_linear(values: np.ndarray) -> np.ndarray:
    """The sRGB decoding curve (IEC 61966-2-1)."""
    v = np.asarray(values, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


# ---------------------------------------------------------------------------- small validators
def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(value, what: str) -> float:
    if not _is_number(value) or not math.isfinite(value):
        raise LfprocError(f"{what} must be a finite number, got {value!r}")
    return float(value)


def _integer(value, what: str, minimum: int) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise LfprocError(f"{what} must be an integer >= {minimum}, got {value!r}")
    return value


def _number_list(value, n: int, what: str) -> list[float]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise LfprocError(f"{what} must be a list of {n} numbers, got {value!r}")
    return [_number(v, what) for v in value]


def _float_tuple(value, n: int, what: str) -> tuple:
    return tuple(_number_list(list(value) if isinstance(value, (list, tuple, np.ndarray)) else value, n, what))


def _check_positive(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value) or value <= 0:
        raise LfprocError(f"texture {what} must be a finite positive number of mm, got {value!r}")


def _check_finite(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value):
        raise LfprocError(f"texture {what} must be a finite number, got {value!r}")


def _check_level(value, what: str) -> None:
    if not _is_number(value) or not math.isfinite(value) or value < 0:
        raise LfprocError(f"texture {what} must be a radiance >= 0, got {value!r}")


def _check_levels(low, high) -> None:
    _check_level(low, "low")
    _check_level(high, "high")
