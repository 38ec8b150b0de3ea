"""Provenance of an output (contract, ARCHITECTURE.md "Provenance"): which files shaped it, by content.

Every sidecar and stack file lfproc writes carries ::

    "provenance": {"lfproc_version": "0.1.0",
                   "inputs": {"capture": {"path": "capture.png", "sha256": "…"}, "camera": {…}, …}}

with the paths as the user gave them and the SHA-256 of each file's bytes; only the inputs that shaped the
output appear (roles :data:`ROLES`). An output made from a saved light field (``.lfp.npz``) records that file
under ``"light_field"`` plus the inputs it was decoded from (stored in the file).

A `LightField` knows its inputs (``LightField.inputs``: role → path, or role → the record already made);
hashes are computed when an output is written, once per file and process (keyed by the file's absolute
path, size and modification time), so a batch of captures hashes its camera, white image and grid once; a
command begins hashing its inputs as it reads them (:func:`sha256_soon`), so that writing finds them done.
Pure standard library.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Mapping

from .errors import LfprocError

#: the roles an input can have, in the order they are listed
ROLES = ("light_field", "capture", "camera", "white", "dark", "grid")

_CHUNK = 1 << 20
_HASHES: dict = {}       # (absolute path, size, mtime) -> hex digest, or the Future of one being computed
_HASHER: list = []       # the one background thread of sha256_soon, made on first use


def sha256_of(path) -> str:
    """The SHA-256 (hex) of a file's bytes, computed once per process for each unchanged file."""
    key = _key(path)
    if key not in _HASHES:
        _HASHES[key] = _digest(key[0], path)
    elif not isinstance(_HASHES[key], str):     # begun by sha256_soon: wait for it here
        try:
            _HASHES[key] = _HASHES[key].result()
        except LfprocError:
            del _HASHES[key]
            raise
    return _HASHES[key]


def sha256_soon(path) -> None:
    """Begin hashing the file ``path`` on a background thread, for :func:`sha256_of` to find done: a command that
    writes outputs seconds after reading its inputs hashes them meanwhile (hashlib works without the GIL), not
    after. Does nothing for a file hashed or being hashed already, or one that cannot be read (then
    :func:`sha256_of` says why)."""
    try:
        key = _key(path)
    except LfprocError:
        return
    if key not in _HASHES:
        if not _HASHER:
            from concurrent.futures import ThreadPoolExecutor
            _HASHER.append(ThreadPoolExecutor(max_workers=1, thread_name_prefix="lfproc-hash"))
        _HASHES[key] = _HASHER[0].submit(_digest, key[0], path)


def _key(path) -> tuple:
    full = os.path.abspath(os.fspath(path))
    try:
        stat = os.stat(full)
    except OSError as exc:
        raise LfprocError(f"{path}: cannot be read ({exc.strerror}); check the path") from None
    return full, stat.st_size, stat.st_mtime_ns


def _digest(full: str, path) -> str:
    """The SHA-256 of the file ``full``, read into one buffer (new ``bytes`` per chunk would stay in the memory of
    the thread that hashes: 8 MB more at a command's peak)."""
    digest = hashlib.sha256()
    buffer = bytearray(_CHUNK)
    view = memoryview(buffer)
    try:
        with open(full, "rb", buffering=0) as fh:
            while size := fh.readinto(buffer):
                digest.update(view[:size])
    except OSError as exc:
        raise LfprocError(f"{path}: cannot be read ({exc.strerror}); check the path") from None
    return digest.hexdigest()


def input_record(path) -> dict:
    """``{"path": path as given, "sha256": hex}`` of one input file."""
    return {"path": os.fspath(path), "sha256": sha256_of(path)}


def input_records(inputs: Mapping | None) -> dict:
    """Role → record of every input in ``inputs`` (role → path, or role → record), in :data:`ROLES` order;
    inputs that are None (an array, a camera built in Python) are left out."""
    out = {}
    for role in sorted((inputs or {}), key=lambda r: ROLES.index(r) if r in ROLES else len(ROLES)):
        value = inputs[role]
        if value is None:
            continue
        if isinstance(value, Mapping):
            out[role] = {"path": str(value["path"]), "sha256": str(value["sha256"])}
        else:
            out[role] = input_record(value)
    return out


def provenance(inputs: Mapping | None) -> dict:
    """The contract's ``provenance`` record of an output shaped by ``inputs`` (role → path or record)."""
    from ._version import __version__

    return {"lfproc_version": __version__, "inputs": input_records(inputs)}


def file_inputs(**paths) -> dict:
    """Role → path for the inputs given as files (``str`` or ``os.PathLike``); arrays and objects are dropped."""
    return {role: os.fspath(p) for role, p in paths.items() if isinstance(p, (str, os.PathLike))}
