"""Derive once, reuse: the decoder's prepared state (and a microscope's deconvolution operators), cached on
disk by the content of what it is made of.

Preparing a :class:`lfproc.decode.Decoder` (the views it delivers, the lenses it keeps, the white
image's resampled inverse) costs more than decoding a capture with it, and depends only on the white
image (and a dark frame, when one is subtracted), the camera, the grid and the decoding settings. So
:func:`cached_decoder` keeps it in a small on-disk cache (see ``docs/cache.md``):

* **Key** (:func:`decoder_key`): SHA-256 of the white image file's bytes (with a Lytro raw's metadata
  file beside it), of the dark frame's, the camera file's text (levels, CFA, m̂), the grid (its lattice
  and smooth deviation), the interpolation and demosaicing, any other decoder option, lfproc's version
  and the source of the code that derives the state (``decode/``, ``io/``, ``grid.py``). Any change to
  any of them is another key: an entry is never stale, it is simply not found.
* **Entry**: one file ``KEY.lfdec``: a JSON header (the decoder's fields: numbers, strings, grids) and
  its arrays, each whole at a page-aligned offset; blocks of an array that are 0 (the views the decoder
  never delivers) are not written (holes of a sparse file: no disk space). Large arrays are read back by
  mapping the file (read-only), not copied: a command or batch worker starts decoding without copying
  hundreds of MB, and processes using one entry share its pages.
  Written atomically (:func:`lfproc.atomic.atomic_path`): a reader sees a whole entry or none.
* **Concurrency**: the process that derives an entry holds an exclusive lock (``KEY.lock``) while it
  does; others wanting the same entry wait for it and then read it, so a batch derives once, not once
  per worker.
* **Bound**: after each write, the least recently used entries are removed until the folder holds at
  most ``LFPROC_CACHE_MAX_GB`` (default 4) GB.
* **Where**: ``$LFPROC_CACHE_DIR/decoders`` (default ``$XDG_CACHE_HOME/lfproc/decoders``, i.e.
  ``~/.cache/lfproc/decoders``); ``LFPROC_NO_CACHE=1`` disables it (every command derives again);
  ``lfproc info --cache`` says where it is and what it holds (:func:`summary`), ``lfproc info
  --clear-cache`` empties it (or remove the folder: nothing else lives there).

The deconvolution's operators (:class:`lfproc.wave.WaveOperators`: the light-field PSFs of a microscope's
voxels) are entries of the same cache (:func:`cached_entry`), keyed by the optics, m̂, the lattice, the depths,
the sampling and the source of ``wave/`` (:func:`operators_key`): every capture of one rig and one z range,
and every process of a batch, shares them.

A cache that cannot be written (read-only or full disk) is skipped with one warning: decoding never
fails because of it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import glob
import hashlib
import json
import os
import struct

import numpy as np

from .errors import LfprocError, warn
from .grid import LensGrid

#: arrays at least this large are mapped from the entry, smaller ones copied (ordinary writable arrays)
MAP_BYTES = 1 << 20
#: bump when the entry layout changes
CACHE_FORMAT = 2
MAGIC = b"LFPDEC01"
ALIGN = 4096
DEFAULT_MAX_GB = 4.0
_CODE_DIGEST: list = []
_WAVE_DIGEST: list = []


# ----------------------------------------------------------------------------- where
def cache_dir() -> str | None:
    """The folder of decoder entries, or None when caching is disabled (``LFPROC_NO_CACHE``)."""
    if os.environ.get("LFPROC_NO_CACHE", "").strip().lower() not in ("", "0", "false", "no"):
        return None
    root = os.environ.get("LFPROC_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "lfproc")
    return os.path.join(root, "decoders")


def max_bytes() -> int:
    """The cache's size bound in bytes (``LFPROC_CACHE_MAX_GB``, default 4 GB)."""
    try:
        gb = float(os.environ.get("LFPROC_CACHE_MAX_GB", DEFAULT_MAX_GB))
    except ValueError:
        gb = DEFAULT_MAX_GB
    return int(max(0.0, gb) * 1e9)


def entries(folder: str | None = None) -> list[str]:
    """Paths of the cache's entries."""
    folder = folder or cache_dir()
    return sorted(glob.glob(os.path.join(glob.escape(folder), "*.lfdec"))) if folder else []


def summary(folder: str | None = None) -> dict | None:
    """``{"folder", "entries", "bytes", "max_bytes"}`` of the cache (disk space its entries take), or None
    when caching is disabled."""
    folder = folder or cache_dir()
    if folder is None:
        return None
    found = entries(folder)
    return {"folder": folder, "entries": len(found), "bytes": sum(disk_bytes(p) for p in found),
            "max_bytes": max_bytes()}


def clear(folder: str | None = None) -> int:
    """Remove every entry (and lock file); the number of entries removed."""
    folder = folder or cache_dir()
    removed = 0
    for path in entries(folder):
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)
            removed += 1
    for path in glob.glob(os.path.join(glob.escape(folder), "*.lock")) if folder else []:
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)
    return removed


# ----------------------------------------------------------------------------- key
def file_digest(path: str) -> str:
    """SHA-256 of a file's SHA-256 (:func:`lfproc.provenance.sha256_of`: once per file and process) and of the
    bytes of a Lytro raw's metadata file (``NAME.txt``/``.json``) beside it."""
    from .provenance import sha256_of

    sha = hashlib.sha256(sha256_of(path).encode() + b"\0")
    stem, ext = os.path.splitext(os.path.abspath(path))
    companions = []
    if ext.lower() == ".raw":
        folder = os.path.dirname(stem)
        companions = sorted(os.path.join(folder, name) for name in os.listdir(folder)
                            if os.path.splitext(name)[0] == os.path.basename(stem)
                            and os.path.splitext(name)[1].lower() in (".txt", ".json"))
    for name in companions:
        with open(name, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 22), b""):
                sha.update(block)
        sha.update(b"\0")
    return sha.hexdigest()


def array_digest(array: np.ndarray, cfa: str = "none") -> str:
    """SHA-256 of an in-memory image (its dtype, shape, CFA and bytes), for a white image not from a file."""
    array = np.ascontiguousarray(array)
    sha = hashlib.sha256(f"{array.dtype.str}{array.shape}{cfa}".encode())
    sha.update(memoryview(array).cast("B"))
    return sha.hexdigest()


def code_digest() -> str:
    """SHA-256 of the source of the code the prepared state comes from (decoding, reading, the grid)."""
    if not _CODE_DIGEST:
        _CODE_DIGEST.append(_source_digest(("decode", "io")))
    return _CODE_DIGEST[0]


def wave_code_digest() -> str:
    """SHA-256 of the source of the deconvolution's operators (``wave/``)."""
    if not _WAVE_DIGEST:
        _WAVE_DIGEST.append(_source_digest(("wave",)))
    return _WAVE_DIGEST[0]


def _source_digest(stages) -> str:
    here = os.path.dirname(os.path.abspath(__file__))
    files = sorted([name for stage in stages for name in glob.glob(os.path.join(here, stage, "*.py"))]
                   + [os.path.join(here, "grid.py"), os.path.abspath(__file__)])
    sha = hashlib.sha256()
    for name in files:
        sha.update(os.path.relpath(name, here).encode() + b"\0")
        with open(name, "rb") as fh:
            sha.update(fh.read())
    return sha.hexdigest()


def grid_identity(grid: LensGrid) -> dict:
    """The grid's defining fields (what ``LensGrid.from_json_dict`` reads; the derived centres left out)."""
    return {"grid": grid.kind, "pitch_px": grid.pitch_px, "rotation_deg": grid.rotation_deg,
            "residual_rms_px": grid.residual_rms_px, "origin_xy_px": list(grid.origin_xy_px), "rows": grid.rows,
            "cols": grid.cols, "deviation": None if grid.deviation is None else grid.deviation.to_json_dict()}


def decoder_key(*, white: str, camera, grid: LensGrid, interpolation: str, demosaic_method: str,
                dark: str | None = None, options: dict | None = None) -> str:
    """The cache key of a decoder: a hex SHA-256 of everything its state depends on (module docstring).

    ``white`` and ``dark`` are content digests (:func:`file_digest`, :func:`array_digest`, or a
    description such as ``"flat 480x640 RGGB"`` for the flat white that stands in for none).
    """
    from . import __version__

    parts = {"format": CACHE_FORMAT, "lfproc": __version__, "code": code_digest(), "white": white, "dark": dark,
             "camera": camera.to_toml(), "grid": grid_identity(grid), "interpolation": interpolation,
             "demosaic_method": demosaic_method, "options": options or {}}
    return hashlib.sha256(json.dumps(parts, sort_keys=True, default=str).encode()).hexdigest()


def operators_key(camera, z_um, superres: int, sample_shift=(0.0, 0.0), oversample=None) -> str:
    """The cache key of a microscope's deconvolution operators (:func:`lfproc.wave.build_operators`): the optics,
    the lenslets, m̂, the depths, S, the view centre, the field's sampling, lfproc and ``wave/``."""
    from . import __version__

    optics = camera.main_optics.wave_optics
    parts = {"format": CACHE_FORMAT, "kind": "wave-operators", "lfproc": __version__, "code": wave_code_digest(),
             "optics": [optics.numerical_aperture, optics.immersion_index, optics.objective_magnification,
                        optics.wavelength_nm],
             "lenslets": [camera.mla_pitch_mm, camera.mla_focal_length_mm, camera.m_hat, camera.grid],
             "z_um": [float(v) for v in z_um], "superres": int(superres),
             "sample_shift": [float(v) for v in sample_shift], "oversample": oversample}
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()


# ----------------------------------------------------------------------------- entries
def _encode(decoder) -> tuple[dict, list]:
    """The header fields and the (name, array, nonzero blocks) to store of a decoder, generically by field."""
    fields, arrays = {}, []
    for f in dataclasses.fields(decoder):
        value = getattr(decoder, f.name)
        if isinstance(value, np.ndarray):
            blocks = _nonzero_blocks(value)
            fields[f.name] = {"array": [value.dtype.str, list(value.shape)],
                              "blocks": None if blocks is None else [list(b) for b in blocks]}
            arrays.append((value, blocks))
        elif isinstance(value, LensGrid):
            fields[f.name] = {"grid": grid_identity(value)}
        else:
            fields[f.name] = {"value": list(value) if isinstance(value, tuple) else value, "tuple":
                              isinstance(value, tuple)}
    return fields, arrays


def _nonzero_blocks(array: np.ndarray):
    """For arrays of 3 or more dimensions, the ``(i, j)`` sub-arrays over the first two axes that are not all
    0 (stored alone); None (stored whole) otherwise."""
    if array.ndim < 3:
        return None
    return [(i, j) for i in range(array.shape[0]) for j in range(array.shape[1]) if array[i, j].any()]


def _aligned(n: int) -> int:
    return n + (-n % ALIGN)


def store(path: str, key: str, decoder) -> None:
    """Write a decoder's entry atomically: each array whole at its page-aligned offset from the data start,
    its zero blocks left as holes."""
    from .atomic import atomic_path

    fields, arrays = _encode(decoder)
    offset = 0
    for spec, (array, _) in zip((spec for spec in fields.values() if "array" in spec), arrays):
        spec["offset"] = offset
        offset = _aligned(offset + array.nbytes)
    header = json.dumps({"format": CACHE_FORMAT, "key": key, "fields": fields}).encode()
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(MAGIC + struct.pack("<Q", len(header)) + header)
            start = _aligned(fh.tell())
            for spec, (array, blocks) in zip((spec for spec in fields.values() if "array" in spec), arrays):
                if blocks is None:
                    fh.seek(start + spec["offset"])
                    fh.write(memoryview(np.ascontiguousarray(array)).cast("B"))
                    continue
                block = array[0, 0].nbytes
                for i, j in blocks:
                    fh.seek(start + spec["offset"] + (i * array.shape[1] + j) * block)
                    fh.write(memoryview(np.ascontiguousarray(array[i, j])).cast("B"))
            fh.truncate(start + offset)    # the zero blocks after the last one written: holes too


def load(path: str, key: str, cls):
    """The decoder of an entry, or None if it is missing, of another key or format, or unreadable."""
    try:
        with open(path, "rb") as fh:
            if fh.read(len(MAGIC)) != MAGIC:
                return None
            (size,) = struct.unpack("<Q", fh.read(8))
            head = json.loads(fh.read(size))
            if head.get("format") != CACHE_FORMAT or head.get("key") != key:
                return None
            start, length = _aligned(fh.tell()), os.fstat(fh.fileno()).st_size
            values = {}
            for name, spec in head["fields"].items():
                if "grid" in spec:
                    values[name] = LensGrid.from_json_dict(spec["grid"], source=path)
                elif "value" in spec:
                    values[name] = tuple(spec["value"]) if spec["tuple"] else spec["value"]
                else:
                    dtype, shape = np.dtype(spec["array"][0]), tuple(spec["array"][1])
                    values[name] = _read_array(fh, start + int(spec["offset"]), dtype, shape, length)
            decoder = cls(**values)
    except (OSError, ValueError, KeyError, TypeError, struct.error, LfprocError):
        return None
    with contextlib.suppress(OSError):
        os.utime(path)        # recently used: pruned last
    return decoder


def _read_array(fh, offset: int, dtype: np.dtype, shape: tuple, length: int) -> np.ndarray:
    """The array at ``offset``: mapped read-only when large (on POSIX systems, where a mapped entry can
    still be replaced or pruned), else copied."""
    import mmap

    nbytes = int(np.prod(shape)) * dtype.itemsize
    if offset + nbytes > length:
        raise ValueError("truncated cache entry")     # mapping past the end would crash on first access
    if nbytes >= MAP_BYTES and os.name == "posix" and offset % mmap.ALLOCATIONGRANULARITY == 0:
        mapped = mmap.mmap(fh.fileno(), nbytes, access=mmap.ACCESS_READ, offset=offset)
        return np.frombuffer(mapped, dtype=dtype).reshape(shape)
    fh.seek(offset)
    array = np.empty(shape, dtype=dtype)
    view = memoryview(array).cast("B") if nbytes else memoryview(b"")
    if nbytes and fh.readinto(view) != nbytes:
        raise ValueError("truncated cache entry")
    return array


def disk_bytes(path: str) -> int:
    """The disk space an entry takes (its holes, the zero blocks, take none)."""
    st = os.stat(path)
    return getattr(st, "st_blocks", -(-st.st_size // 512)) * 512


def prune(folder: str, limit: int, keep: str | None = None) -> None:
    """Remove the least recently used entries until the folder holds at most ``limit`` bytes (not ``keep``)."""
    found = []
    for path in entries(folder):
        with contextlib.suppress(FileNotFoundError):
            found.append((os.stat(path).st_mtime, disk_bytes(path), path))
    total = sum(size for _, size, _ in found)
    for _, size, path in sorted(found):
        if total <= limit:
            break
        if path == keep:
            continue
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)
        with contextlib.suppress(FileNotFoundError):
            os.remove(path[:-len(".lfdec")] + ".lock")
        total -= size


@contextlib.contextmanager
def _locked(path: str):
    """An exclusive lock on ``path`` (created if needed) for the duration; no lock where the OS has none."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: concurrent writers stay correct (atomic rename)
        yield
        return
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)   # releases the lock


def cached_decoder(key: str, build):
    """The decoder of ``key`` from the cache, else ``build()`` stored there (one builder per key at a time).

    Without a cache (``LFPROC_NO_CACHE``), or one that cannot be written, this is ``build()``.
    """
    from .decode import Decoder

    return cached_entry(key, build, Decoder)


def cached_entry(key: str, build, cls):
    """The entry of ``key`` (a frozen dataclass ``cls`` of arrays, grids and plain values) from the cache, else
    ``build()`` stored there (one builder per key at a time); ``build()`` alone without a writable cache."""
    folder = cache_dir()
    if folder is None:
        return build()
    path = os.path.join(folder, key + ".lfdec")
    found = load(path, key, cls)
    if found is not None:
        return found
    try:
        os.makedirs(folder, exist_ok=True)
        lock = _locked(os.path.join(folder, key + ".lock"))
        lock.__enter__()
    except OSError as exc:
        warn(f"lfproc cache {folder}: not writable ({exc.strerror or exc}); deriving without it "
             f"(set LFPROC_CACHE_DIR, or LFPROC_NO_CACHE=1)")
        return build()
    try:
        found = load(path, key, cls)   # another process may have derived it while we waited
        if found is not None:
            return found
        entry = build()
        try:
            store(path, key, entry)
            prune(folder, max_bytes(), keep=path)
        except Exception as exc:  # noqa: BLE001 - a full or read-only disk must not fail the decode
            warn(f"lfproc cache {folder}: could not store an entry ({exc}); continuing without it")
        return entry
    finally:
        lock.__exit__(None, None, None)
