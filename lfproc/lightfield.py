"""`LightField`: the decoded 4-D light field, its camera and lens grid, and its file format.

Layout (contract): ``views[ky, kx, jy, jx, ch]`` — view row, view column, lens row, lens column,
channel — float32, linear, with m̂ × m̂ views (m̂ odd). View index k increases with the sensor
coordinate like the lens index j; the central view is k = c = (m̂ − 1)/2.

File format (``.lfp.npz``, written by :meth:`LightField.save`): an uncompressed numpy ``.npz``
archive with the members ``views`` (the array above), ``camera_toml`` (the camera file, a string;
empty if none) and ``grid_json`` (the lens grid as written by ``lfproc calibrate``; empty if none),
optionally ``view_mask`` ((m̂, m̂) bool, the views that carry light; absent when all do) and
``view_centre`` (2 float64 (c_y, c_x): where the central view was read, in samples off the lens centres;
absent when at them), optionally ``inputs_json`` (the files it was decoded from, role → ``{"path", "sha256"}``,
:mod:`lfproc.provenance`), plus ``format`` = ``"lfproc-lightfield-1"``. Any numpy can read it:
``np.load(path)["views"]``.
"""

from __future__ import annotations

import json
import os
import zipfile
from dataclasses import dataclass

import numpy as np

from .atomic import atomic_path
from .camera import Camera
from .errors import LfprocError
from .grid import LensGrid

#: how a message tells a Python caller to write a light field file (the commands word it as `lfproc decode`)
SAVE_AGAIN = "`lfproc.read_light_field(...).save(path)`"

FILE_FORMAT = "lfproc-lightfield-1"


def output_stem(path: str) -> str:
    """The name outputs of a capture start with: its file name without extension (``.lfp.npz`` as one)."""
    name = os.path.basename(path)
    if name.lower().endswith(".lfp.npz"):
        return name[:-len(".lfp.npz")]
    return os.path.splitext(name)[0]


def is_lightfield_file(path) -> bool:
    """A light field written by ``lfproc decode`` (``NAME.lfp.npz``; any ``.npz``, any case), by its name."""
    return os.fspath(path).lower().endswith(".npz")


@dataclass(frozen=True, eq=False)
class LightField:
    """A decoded light field: ``views`` shaped ``(m̂, m̂, Ny, Nx, C)`` plus optional camera and grid.

    ``view_mask`` (m̂, m̂) bool, optional, marks the views that carry light: the decoder leaves views
    outside the main lens aperture or too close to a micro image's rim at 0 (see :mod:`lfproc.decode`),
    and refocusing averages over the marked views only, so slices keep the scene's brightness. ``None``:
    every view carries light. The views it leaves out must be 0 (:meth:`from_views` sets them so).

    ``view_centre`` (c_y, c_x), optional: where the decoder read the central view, in samples (p_m/m̂) off
    each lens centre along the lattice's v and u axes. The decoder reads the views around the lit disc's
    centre (:mod:`lfproc.decode._disc_centre`); where that is off the lens centre (an objective pupil off
    the axis, a tilted illumination) view k stands for the ray at (k − c + view_centre)·p_m/m̂ under its
    lens, and the views' angles and the sine condition's shifts follow it. ``None``: at the lens centres.

    ``inputs``, optional: the files it was made from, role (``"capture"``, ``"camera"``, ``"white"``,
    ``"dark"``, ``"grid"``, ``"light_field"``) → path as given (or an already hashed ``{"path", "sha256"}``
    record); outputs record them as their provenance (:mod:`lfproc.provenance`). ``None``: unknown (arrays).

    Attributes
    ----------
    views : ndarray, shape (m̂, m̂, Ny, Nx, C)
        The views (Eq. 32), linear; float32 as decoded.
    camera : Camera or None
    grid : LensGrid or None
        The lattice the views were decoded along (pixels of the sensor).
    view_mask : ndarray (m̂, m̂) bool or None
    view_centre : (float, float) or None
    inputs : dict or None
        As above.
    """

    views: np.ndarray
    camera: Camera | None = None
    grid: LensGrid | None = None
    view_mask: np.ndarray | None = None
    view_centre: tuple | None = None
    inputs: dict | None = None

    def __repr__(self) -> str:
        m, _, ny, nx, c = self.views.shape
        lit = m * m if self.view_mask is None else int(np.count_nonzero(self.view_mask))
        camera = "none" if self.camera is None else repr(self.camera.name or self.camera.source or "unnamed")
        source = self.source
        return (f"<LightField {m}x{m} views ({lit} carry light) of {ny}x{nx} lenses, {c} channel(s), "
                f"camera {camera}{f', from {source!r}' if source else ''}>")

    @property
    def source(self) -> str | None:
        """The file this light field was read from (a saved light field, else the capture), as given; None
        for arrays."""
        inputs = self.inputs or {}
        for role in ("light_field", "capture"):
            value = inputs.get(role)
            if value is not None:
                return str(value["path"]) if isinstance(value, dict) else os.fspath(value)
        return None

    def __post_init__(self):
        v = self.views
        if v.ndim != 5 or v.shape[0] != v.shape[1] or v.shape[0] % 2 == 0:
            raise LfprocError(f"light field views must be shaped (m, m, Ny, Nx, C) with m odd, got {v.shape}")
        if min(v.shape) < 1:
            raise LfprocError(f"light field views must not be empty, got shape {v.shape}")
        if self.view_mask is not None:
            mask = np.asarray(self.view_mask, dtype=bool)
            if mask.shape != v.shape[:2] or not mask.any():
                raise LfprocError(f"light field view_mask must be {v.shape[0]}x{v.shape[0]} booleans marking at least "
                                  f"one view, got shape {mask.shape}")
            if not mask.all() and _any_nonzero(v, ~mask):
                raise LfprocError("light field views that view_mask leaves out must be 0 (refocusing sums every "
                                  "view); build it with LightField.from_views, which zeroes them")
            object.__setattr__(self, "view_mask", None if mask.all() else mask)
        if self.view_centre is not None:
            try:
                centre = tuple(float(x) for x in self.view_centre)
            except (TypeError, ValueError):
                centre = ()
            if len(centre) != 2 or not all(np.isfinite(centre)):
                raise LfprocError(f"light field view_centre must be two finite numbers (c_y, c_x), "
                                  f"got {self.view_centre!r}")
            object.__setattr__(self, "view_centre", None if centre == (0.0, 0.0) else centre)
        if self.camera is not None and self.camera.m_hat != v.shape[0]:
            raise LfprocError(f"light field has {v.shape[0]}x{v.shape[0]} views but the camera's micro_image_px "
                              f"is {self.camera.m_hat}; decode with that camera or fix decode.micro_image_px")

    @classmethod
    def from_views(cls, views, camera: Camera | None = None, grid: LensGrid | None = None,
                   view_mask=None, view_centre=None, inputs=None) -> "LightField":
        """Wrap an array shaped ``(m̂, m̂, Ny, Nx, C)``; it is converted to float32 (no copy if it already is)."""
        arr = np.asarray(views)
        if arr.dtype != np.float32:
            source = arr
            with np.errstate(over="ignore"):
                arr = arr.astype(np.float32)
            if np.issubdtype(source.dtype, np.floating) and not np.isfinite(arr).all() and np.isfinite(source).all():
                raise LfprocError("light field values exceed the float32 range (|x| > 3.4e38); rescale them first")
        arr = np.ascontiguousarray(arr)
        if view_mask is not None:
            unmarked = ~np.asarray(view_mask, dtype=bool)
            if unmarked.shape == arr.shape[:2] and unmarked.any() and _any_nonzero(arr, unmarked):
                arr = arr.copy() if arr is views else arr
                arr[unmarked] = 0.0
        return cls(arr, camera, grid, view_mask, view_centre, None if inputs is None else dict(inputs))

    @property
    def m_hat(self) -> int:
        return int(self.views.shape[0])

    @property
    def center_index(self) -> int:
        return (self.m_hat - 1) // 2

    @property
    def lens_shape(self) -> tuple[int, int]:
        return int(self.views.shape[2]), int(self.views.shape[3])

    @property
    def channels(self) -> int:
        return int(self.views.shape[4])

    @property
    def effective_pixel_pitch_mm(self) -> float | None:
        return None if self.camera is None else self.camera.effective_pixel_pitch_mm

    @property
    def refocus_slopes(self):
        """Per-view shift table (σ_y, σ_x) for :func:`lfproc.refocus`, or ``None`` for Eq. 9's a·(c − k).

        Only a camera whose refocusing follows the sine condition (a high-NA microscope) has one
        (:func:`lfproc.geometry.refocus_slopes`, ``None`` for every other camera); its m̂ must match the views.
        """
        if self.camera is None or self.camera.m_hat != self.m_hat:
            return None
        from .geometry import refocus_slopes     # numpy only: stays light
        return refocus_slopes(self.camera, centre=self.view_centre)

    # ------------------------------------------------------------------ file format
    def save(self, path: str | os.PathLike) -> None:
        """Write the light field atomically in the format of the module docstring."""
        camera_toml = self.camera.to_toml() if self.camera is not None else ""
        grid_json = json.dumps(self.grid.to_json_dict()) if self.grid is not None else ""
        with atomic_path(path, suffix=".npz") as tmp:
            with open(tmp, "wb") as fh:
                extra = {} if self.view_mask is None else {"view_mask": self.view_mask}
                if self.view_centre is not None:
                    extra["view_centre"] = np.array(self.view_centre, dtype=np.float64)
                if self.inputs:
                    from .provenance import input_records
                    extra["inputs_json"] = np.array(json.dumps(input_records(self.inputs)))
                np.savez(fh, views=self.views, camera_toml=np.array(camera_toml),
                         grid_json=np.array(grid_json), format=np.array(FILE_FORMAT), **extra)

    @classmethod
    def read_camera(cls, path: str | os.PathLike) -> Camera | None:
        """The camera a light field file carries (``None`` if it has none), without reading its views."""
        path = os.fspath(path)
        camera_toml = str(_read_members(path, ("camera_toml",))["camera_toml"])
        return Camera.from_toml_string(camera_toml, source=path) if camera_toml else None

    @classmethod
    def load(cls, path: str | os.PathLike) -> "LightField":
        """Read a light field written by :meth:`save` (``lfproc decode``'s ``.lfp.npz``).

        Parameters
        ----------
        path : str or os.PathLike
            The ``.lfp.npz`` file.

        Returns
        -------
        LightField
            Its views ``(m̂, m̂, Ny, Nx, C)`` float32, the camera and lens grid it was decoded with (``None``
            where the file has none) and the view mask (``None`` when every view carries light).

        Raises
        ------
        LfprocError
            A missing or unreadable file, or one that is not a light field (arrays of the wrong shape or
            type; pickled objects are never loaded).
        """
        path = os.fspath(path)
        members = _read_members(path, ("views", "camera_toml", "grid_json"),
                                optional=("view_mask", "view_centre", "inputs_json"))
        views, camera_toml, grid_json = members["views"], str(members["camera_toml"]), str(members["grid_json"])
        camera = Camera.from_toml_string(camera_toml, source=path) if camera_toml else None
        grid = LensGrid.from_json_dict(_grid_document(grid_json, path), source=path) if grid_json else None
        if views.dtype.kind not in "fiub":
            raise LfprocError(f"{path}: its views are {views.dtype} data, not numbers; write it again with "
                              f"{SAVE_AGAIN}")
        centre = members.get("view_centre")
        inputs = {"light_field": path, **_stored_inputs(members.get("inputs_json"), path)}
        return cls.from_views(views, camera, grid, members.get("view_mask"), None if centre is None else
                              tuple(np.asarray(centre, dtype=np.float64).reshape(-1)), inputs)


def _stored_inputs(member, path: str) -> dict:
    """The inputs a light field file says it was decoded from (role → ``{"path", "sha256"}``); a damaged record
    is refused, an older file without one has none."""
    if member is None:
        return {}
    try:
        stored = json.loads(str(member))
        records = {str(role): {"path": str(r["path"]), "sha256": str(r["sha256"])} for role, r in stored.items()
                   if role != "light_field"}
    except (ValueError, TypeError, KeyError, AttributeError):
        raise LfprocError(f"{path}: its inputs_json record is damaged; write it again with {SAVE_AGAIN}") from None
    return records


def _any_nonzero(views: np.ndarray, which: np.ndarray) -> bool:
    """Whether any of the views ``which`` marks holds a nonzero value: view by view, no copy (the views
    a decoder never wrote are never-touched zero memory, and stay so)."""
    return any(views[ky, kx].any() for ky, kx in zip(*np.nonzero(which)))


def _grid_document(grid_json: str, path: str) -> dict:
    try:
        document = json.loads(grid_json)
    except ValueError as exc:
        raise LfprocError(f"{path}: its grid_json is not JSON ({exc}); write it again with {SAVE_AGAIN}") from None
    if not isinstance(document, dict):
        raise LfprocError(f"{path}: its grid_json is not a grid; write it again with {SAVE_AGAIN}")
    return document


def _read_members(path: str, names: tuple, optional: tuple = ()) -> dict:
    """The named arrays of a light field file (only those are read), every failure as one LfprocError.

    Before numpy reads a member, its header is checked against the bytes the archive holds for it (a
    declared shape the file cannot hold is refused before anything is allocated for it), and members
    of Python objects are refused: lfproc never unpickles (``allow_pickle=False``).
    """
    try:
        with zipfile.ZipFile(path) as archive:
            infos = {info.filename[:-4]: info for info in archive.infolist() if info.filename.endswith(".npy")}
            if "format" not in infos:
                raise LfprocError(f"{path}: not an lfproc light field file; write one with {SAVE_AGAIN}")
            for name in ("format", *names, *(n for n in optional if n in infos)):
                if name not in infos:
                    raise LfprocError(f"{path}: the light field file has no '{name}'; write it again with "
                                      f"{SAVE_AGAIN}")
                _check_member(archive, infos[name], name, path)
        with np.load(path, allow_pickle=False) as data:
            if str(data["format"]) != FILE_FORMAT:
                raise LfprocError(f"{path}: not an lfproc light field file; write one with {SAVE_AGAIN}")
            members = {name: data[name] for name in names}
            members.update({name: data[name] for name in optional if name in data})
            return members
    except FileNotFoundError:
        raise LfprocError(f"{path}: light field file not found; check the path") from None
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, KeyError, NotImplementedError,
            RuntimeError) as exc:
        raise LfprocError(f"{path}: cannot read light field file ({exc}); write it again with {SAVE_AGAIN}") \
            from None


#: a deflated member may expand at most this much (deflate's limit is about 1032:1)
_MAX_INFLATION = 1100


def _check_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str, path: str) -> None:
    """Refuse a member that holds Python objects or declares more data than the archive holds for it."""
    import math

    if info.compress_size > os.path.getsize(path) or \
            info.file_size > _MAX_INFLATION * info.compress_size + (1 << 20):
        raise LfprocError(f"{path}: member '{name}' declares sizes the file cannot hold; the file is corrupt, "
                          f"write it again with {SAVE_AGAIN}")
    import tokenize

    with archive.open(info) as fh:
        version = np.lib.format.read_magic(fh)
        if version not in ((1, 0), (2, 0)):
            raise LfprocError(f"{path}: member '{name}' has numpy format version {version}; write it again with "
                              f"{SAVE_AGAIN}")
        try:
            read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
                np.lib.format.read_array_header_2_0
            shape, _, dtype = read_header(fh)
        except (ValueError, TypeError, SyntaxError, tokenize.TokenError) as exc:
            raise LfprocError(f"{path}: member '{name}' has a corrupt header ({type(exc).__name__}); write it "
                              f"again with {SAVE_AGAIN}") from None
        header_bytes = fh.tell()
    if dtype.hasobject:
        raise LfprocError(f"{path}: member '{name}' holds Python objects, which lfproc never unpickles; write the "
                          f"file again with {SAVE_AGAIN}")
    declared = math.prod(shape) * dtype.itemsize
    if declared > info.file_size - header_bytes:
        raise LfprocError(f"{path}: member '{name}' declares {shape} {dtype} ({declared} bytes) but holds "
                          f"{info.file_size - header_bytes}; the file is truncated or corrupt, write it again with "
                          f"{SAVE_AGAIN}")
