"""Lytro frame metadata: sensor size, packing, levels per Bayer channel, CFA, optics, serial, motor steps.

Key names and units are those of ``lytro-format.md`` (SI units in the file: metres, radians); what
each becomes is listed in ``docs/lytro.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import LfprocError

#: ``mosaic.upperLeftPixel`` -> Bayer pattern (the colours of pixels (0,0), (0,1), (1,0), (1,1))
UPPER_LEFT_TO_CFA = {"r": "RGGB", "gr": "GRBG", "gb": "GBRG", "b": "BGGR"}
#: exit pupil offsets at or beyond this (metres) mean "at infinity" (F01 files write 10000)
INFINITE_EXIT_PUPIL_M = 100.0
_CHANNELS = ("r", "gr", "gb", "b")


@dataclass(frozen=True)
class LytroMetadata:
    """What lfproc uses from a Lytro frame's metadata (lengths in metres, angles in radians, as stored).

    ``black``/``white`` are ``(2, 2)`` tuples of the levels at (row % 2, column % 2), read per Bayer
    channel from ``image.rawDetails.pixelFormat`` (``image.pixelFormat`` in an Illum picture's metadata:
    ``raw_details_key`` says which). Optics are ``None`` where the file lacks them.
    """

    source: str
    model: str
    serial: str | None
    width: int
    height: int
    bits_per_pixel: int
    endianness: str
    cfa: str
    black: tuple
    white: tuple
    pixel_pitch_m: float | None = None
    lens_pitch_m: float | None = None
    tiling: str | None = None
    rotation_rad: float | None = None
    scale_factor: tuple | None = None
    sensor_offset_m: tuple | None = None
    focal_length_m: float | None = None
    f_number: float | None = None
    exit_pupil_offset_m: float | None = None
    zoom_step: float | None = None
    focus_step: float | None = None
    infinity_lambda: float | None = None
    modulation_frame: bool | None = None
    raw_details_key: str = "image.rawDetails"

    @property
    def packed_bytes(self) -> int:
        """The byte count the packed raw must have: width · height · bits / 8."""
        return self.width * self.height * self.bits_per_pixel // 8

    @property
    def exit_pupil_at_infinity(self) -> bool:
        return self.exit_pupil_offset_m is None or self.exit_pupil_offset_m >= INFINITE_EXIT_PUPIL_M

    def levels(self) -> tuple[np.ndarray, np.ndarray]:
        """``(black, white)`` as float ``(2, 2)`` arrays per CFA position."""
        return np.asarray(self.black, float), np.asarray(self.white, float)


def frame_metadata(document: dict, where: str) -> tuple[dict, dict | None, bool | None]:
    """The frame metadata, private metadata and modulation flag of a raw pair's JSON document.

    The F01 writes the frame metadata at the top level; the Illum under
    ``master.picture.frameArray[0].frame.metadata``, with ``privateMetadata`` beside it.
    """
    from ._lytro_container import modulation_flag

    if not isinstance(document, dict):
        raise LfprocError(f"{where}: not Lytro frame metadata (not a JSON object); pass the .txt/.json written "
                          f"with the raw image")
    if isinstance(document.get("image"), dict):
        return document, _dict_or_none(document.get("privateMetadata")), None
    try:
        entry = document["master"]["picture"]["frameArray"][0]
        frame = entry["frame"]
        return frame["metadata"], _dict_or_none(frame.get("privateMetadata")), modulation_flag(entry)
    except (KeyError, IndexError, TypeError):
        raise LfprocError(f"{where}: not Lytro frame metadata (no 'image' or 'master.picture.frameArray'); "
                          f"pass the .txt/.json written with the raw image") from None


def parse_metadata(metadata: dict, private: dict | None, source: str, modulation_frame=None) -> LytroMetadata:
    """Read a frame's metadata into a `LytroMetadata` (errors name ``source`` and the key)."""
    image = _get(metadata, "image", source, dict)
    representation = image.get("representation", "rawPacked")
    if representation != "rawPacked":
        raise LfprocError(f"{source}: holds no raw light field (its image is {representation!r}, not packed raw "
                          f"sensor data); pass the camera's original raw picture instead")
    if not isinstance(image.get("rawDetails"), dict) and isinstance(image.get("pixelPacking"), dict):
        raw, key = image, "image"   # the Illum picture schema: the raw frame's packing, levels, mosaic under image
    else:
        raw, key = _get(image, "rawDetails", source, dict, "image."), "image.rawDetails"
    packing = _get(raw, "pixelPacking", source, dict, key + ".")
    width = _get(image, "width", source, int, "image.")
    height = _get(image, "height", source, int, "image.")
    if width <= 0 or height <= 0 or width * height > 1 << 40:  # no sensor has a trillion pixels
        raise LfprocError(f"{source}: image.width/height {width} x {height} is not a sensor size; "
                          f"the metadata is corrupt, re-copy it")
    bits = _get(packing, "bitsPerPixel", source, int, key + ".pixelPacking.")
    if not 1 <= bits <= 32:  # before 2 ** bits below: an absurd value would take for ever
        raise LfprocError(f"{source}: {key}.pixelPacking.bitsPerPixel {bits} is not a sensor's bit "
                          f"depth; the metadata is corrupt, re-copy it")
    endianness = str(_get(packing, "endianness", source, str, key + ".pixelPacking.")).lower()
    mosaic = raw.get("mosaic") or _nested(metadata, "devices", "sensor", "mosaic") or {}
    mosaic = mosaic if isinstance(mosaic, dict) else {}
    cfa, channels = _bayer_layout(mosaic, source)
    pixel_format = raw.get("pixelFormat") if isinstance(raw.get("pixelFormat"), dict) else {}
    if pixel_format.get("rightShift", 0) not in (0, None):
        raise LfprocError(f"{source}: {key}.pixelFormat.rightShift = {pixel_format['rightShift']} is not "
                          f"supported; only unshifted raw data can be read")
    black = _channel_levels(pixel_format.get("black"), channels, 0.0, source, f"{key}.pixelFormat.black")
    white = _channel_levels(pixel_format.get("white"), channels, float(2 ** bits - 1), source,
                            f"{key}.pixelFormat.white")
    if any(not 0 <= b < w <= 2 ** bits for w_row, b_row in zip(white, black) for w, b in zip(w_row, b_row)):
        raise LfprocError(f"{source}: white level {white} is not above the black level {black} within "
                          f"0..{2 ** bits} ({bits}-bit data); the metadata is corrupt, re-copy it")
    devices = metadata.get("devices") if isinstance(metadata.get("devices"), dict) else {}
    sensor, mla, lens = (devices.get(k) if isinstance(devices.get(k), dict) else {} for k in ("sensor", "mla", "lens"))
    return LytroMetadata(
        source=source,
        model=str(_nested(metadata, "camera", "model") or "unknown"),
        serial=_serial(private),
        width=width, height=height, bits_per_pixel=bits, endianness=endianness,
        cfa=cfa, black=black, white=white,
        pixel_pitch_m=_number(sensor.get("pixelPitch")),
        lens_pitch_m=_number(mla.get("lensPitch")),
        tiling=mla.get("tiling") if isinstance(mla.get("tiling"), str) else None,
        rotation_rad=_number(mla.get("rotation")),
        scale_factor=_pair(mla.get("scaleFactor"), "x", "y"),
        sensor_offset_m=_triple(mla.get("sensorOffset")),
        focal_length_m=_number(lens.get("focalLength")),
        f_number=_number(lens.get("fNumber")),
        exit_pupil_offset_m=_number(_nested(lens, "exitPupilOffset", "z")),
        zoom_step=_number(lens.get("zoomStep")),
        focus_step=_number(lens.get("focusStep")),
        infinity_lambda=_number(lens.get("infinityLambda")),
        modulation_frame=modulation_frame,
        raw_details_key=key,
    )


def _bayer_layout(mosaic: dict, source: str) -> tuple[str, tuple]:
    """The CFA pattern and the channel names at the 2×2 positions, from ``tile`` and ``upperLeftPixel``."""
    tile = str(mosaic.get("tile", "r,gr:gb,b")).replace(" ", "")
    rows = [row.split(",") for row in tile.split(":")]
    names = [name for row in rows for name in row]
    upper_left = str(mosaic.get("upperLeftPixel", "")).lower()
    if len(rows) != 2 or any(len(row) != 2 for row in rows) or sorted(names) != sorted(_CHANNELS) \
            or upper_left not in UPPER_LEFT_TO_CFA:
        raise LfprocError(f"{source}: unknown Bayer layout (mosaic.tile {tile!r}, upperLeftPixel {upper_left!r}); "
                          f"expected tile 'r,gr:gb,b' and upperLeftPixel r, gr, gb or b")
    index = names.index(upper_left)
    dy, dx = divmod(index, 2)
    channels = tuple(tuple(rows[(y + dy) % 2][(x + dx) % 2] for x in range(2)) for y in range(2))
    cfa = "".join("G" if name in ("gr", "gb") else name.upper() for row in channels for name in row)
    return cfa, channels


def _channel_levels(levels, channels, default: float, source: str, what: str) -> tuple:
    if levels is None:
        return tuple(tuple(default for _ in row) for row in channels)
    if isinstance(levels, (int, float)) and not isinstance(levels, bool) and _number(levels) is not None:
        return tuple(tuple(float(levels) for _ in row) for row in channels)
    if not isinstance(levels, dict) or any(_number(levels.get(name)) is None for row in channels for name in row):
        raise LfprocError(f"{source}: {what} must give a number for each of "
                          f"r, gr, gb, b; got {levels!r}")
    return tuple(tuple(float(levels[name]) for name in row) for row in channels)


def _get(table: dict, key: str, source: str, kind, prefix: str = ""):
    value = table.get(key) if isinstance(table, dict) else None
    if kind is int and isinstance(value, float) and value.is_integer():
        value = int(value)
    if value is None or isinstance(value, bool) or not isinstance(value, kind):
        raise LfprocError(f"{source}: the metadata lacks {prefix}{key} (or it is not a {kind.__name__}); "
                          f"pass the metadata file written with this raw image")
    return value


def _nested(table, *keys):
    for key in keys:
        if not isinstance(table, dict):
            return None
        table = table.get(key)
    return table


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)


def _pair(table, a: str, b: str):
    if not isinstance(table, dict) or _number(table.get(a)) is None or _number(table.get(b)) is None:
        return None
    return (float(table[a]), float(table[b]))


def _triple(table):
    if not isinstance(table, dict) or any(_number(table.get(k)) is None for k in "xyz"):
        return None
    return tuple(float(table[k]) for k in "xyz")


def _serial(private) -> str | None:
    serial = _nested(private, "camera", "serialNumber")
    return str(serial) if serial not in (None, "") else None


def _dict_or_none(value):
    return value if isinstance(value, dict) else None
