"""A focal stack as one file: an ImageJ hyperstack TIFF or an OME-TIFF with its physical spacing.

Besides the per-slice images and sidecars, ``lfproc refocus --stack`` writes all slices of a capture
into one multi-page TIFF that Fiji/ImageJ (hyperstack) or Bio-Formats and napari (OME-TIFF) open as a
z-stack at its physical scale:

microscope captures
    x/y spacing = the object-space size of one lens (lenslet pitch / objective magnification, Levoy
    et al. 2006) divided by ``upsample``; z spacing = the step between the slices' ``z_um`` (object
    space, positive towards the objective); slices ordered by increasing z. Unit: micron.
photographic captures
    the slices lie at distances that are not evenly spaced and have no single lateral scale, so the
    spacing is one (pixel units) and each slice's ``a`` and ``distance_mm`` go into the metadata: the
    ImageJ slice labels and ``Info``, the OME planes' ``PositionZ`` (mm from the sensor).

Every slice's full sidecar record is stored as JSON (ImageJ ``Info``, OME ``Description``). Written
atomically; tifffile loads only here.
"""

from __future__ import annotations

import json
import math

import numpy as np

from ..atomic import atomic_path, json_safe
from ..errors import LfprocError

#: ``--stack`` kinds and their file name endings
STACK_KINDS = {"imagej": "_stack.tif", "ome": "_stack.ome.tif"}

#: relative unevenness of the z steps below which a stack counts as evenly spaced
EVEN_TOLERANCE = 1e-6


def lateral_um_per_lens(camera) -> float | None:
    """Object-space size of one lens in µm where every depth shares one lateral scale (object-side telecentric
    optics, a microscope: pitch / M, :meth:`lfproc.camera.MainOptics.lateral_sampling_um`), ``None`` for a
    photographic camera (its scale changes with depth)."""
    return camera.main_optics.lateral_sampling_um(camera)


def stack_path(outdir: str, stem: str, kind: str) -> str:
    import os

    if kind not in STACK_KINDS:
        raise LfprocError(f"unknown stack kind {kind!r}; use one of {', '.join(STACK_KINDS)}")
    return os.path.join(outdir, stem + STACK_KINDS[kind])


def stack_axis(records: list[dict], space) -> tuple[np.ndarray, np.ndarray]:
    """The stack's order (indices into ``records``: increasing ``a``, or increasing position where the records
    have no ``a``, as a deconvolved volume's planes) and each slice's position in ``space`` (the record's
    ``space.position_key``: ``z_um`` of a microscope, ``distance_mm`` of a camera; NaN without)."""
    position = np.array([r.get(space.position_key, math.nan) for r in records], dtype=np.float64)
    key = np.array([r["a"] for r in records], dtype=np.float64) if all("a" in r for r in records) else position
    order = np.argsort(key, kind="stable")
    return order, position[order]


def z_spacing_um(z_um: np.ndarray) -> float:
    """The step of evenly spaced ``z_um`` (the mean step otherwise; 1 for a single slice)."""
    if len(z_um) < 2:
        return 1.0
    steps = np.diff(z_um)
    return float(steps.mean()) if steps.mean() > 0 else 1.0


def write_focal_stack(path: str, images: np.ndarray, records: list[dict], space, *, kind: str = "imagej",
                      lens_um: float | None = None, upsample: int = 1, product: str | None = None) -> str:
    """Write the slices ``images`` (``(K, H, W, C)`` float32) as one z-stack file; returns ``path``.

    Parameters
    ----------
    path : str
        Target file (``…_stack.tif`` or ``…_stack.ome.tif``, :func:`stack_path`).
    images : ndarray
        The refocused slices in the order of ``records``.
    records : list of dict
        Each slice's sidecar fields (``a`` and ``distance_mm``, or ``z_um`` for a microscope).
    space : lfproc.camera.ObjectSpace
        The space of the records' positions (``camera.main_optics.object_space``).
    kind : {"imagej", "ome"}
    lens_um : float or None
        Object-space size of one lens in µm (:func:`lateral_um_per_lens`): the stack is then to scale, x, y and z
        in µm; ``None``: pixel units.
    upsample : int
        The slices' upsampling: the pixel is ``lens_um / upsample``.
    product : str, optional
        What the stack is, when it is not a focal stack (``"deconvolved volume"``): recorded with the slices'
        records, where ``lfproc info`` reads it.
    """
    import tifffile

    images = np.asarray(images, dtype=np.float32)
    if images.ndim != 4 or images.shape[0] != len(records):
        raise LfprocError(f"{path}: a stack needs (K, H, W, C) slices, one per record; got {images.shape} "
                          f"for {len(records)} record(s)")
    order, position = stack_axis(records, space)
    data = np.ascontiguousarray(np.moveaxis(images[order], 3, 1))        # (Z, C, Y, X)
    channels = data.shape[1]
    axes = "ZCYX" if channels > 1 else "ZYX"
    if channels == 1:
        data = data[:, 0]
    metric = lens_um is not None     # one lateral scale: x, y and the positions (in µm) to scale
    pixel = lens_um / upsample if metric else 1.0
    dz = z_spacing_um(position * (1000.0 / space.per_mm)) if metric else 1.0
    ordered = [records[i] for i in order]
    labels = [_label(r, space) for r in ordered for _ in range(channels)]
    info = json.dumps(json_safe({**({"product": product} if product else {}), "slices": ordered,
                                 "pixel_um": pixel if metric else None,
                                 "z_spacing_um": dz if metric else None,
                                 "evenly_spaced": _even(position) if metric else None}), allow_nan=False)
    with atomic_path(path, suffix=".tif") as tmp:
        if kind == "imagej":
            tifffile.imwrite(tmp, data, imagej=True, resolution=(1.0 / pixel, 1.0 / pixel),
                             metadata={"axes": axes, "spacing": dz, "unit": "micron" if metric else "pixel",
                                       "Labels": labels, "Info": info})
        elif kind == "ome":
            meta = {"axes": axes, "Description": info,
                    "Plane": {"PositionZ": [float(p) if math.isfinite(p) else 0.0 for p in position
                                            for _ in range(channels)],
                              "PositionZUnit": [space.symbol] * (len(position) * channels)}}
            if metric:
                meta.update(PhysicalSizeX=pixel, PhysicalSizeXUnit="µm", PhysicalSizeY=pixel,
                            PhysicalSizeYUnit="µm", PhysicalSizeZ=dz, PhysicalSizeZUnit="µm")
            meta["UUID"] = _content_uuid(data, info)     # the same stack, the same bytes (not the clock's UUID)
            tifffile.imwrite(tmp, data, ome=True, metadata=meta)
        else:
            raise LfprocError(f"unknown stack kind {kind!r}; use one of {', '.join(STACK_KINDS)}")
    return path


def _content_uuid(data: np.ndarray, info: str) -> str:
    """A name-based UUID (RFC 4122 version 5) of an OME-TIFF's pixels and records: unique per content, and the
    same on every run, so that writing a stack again (a batch, a rerun) gives the same file byte for byte."""
    import hashlib
    import uuid

    digest = hashlib.sha256(np.ascontiguousarray(data).tobytes() + info.encode()).hexdigest()
    return f"urn:uuid:{uuid.uuid5(uuid.NAMESPACE_URL, 'lfproc:ome-tiff:' + digest)}"


def _even(z: np.ndarray) -> bool:
    if len(z) < 3:
        return True
    steps = np.diff(z)
    return bool(np.ptp(steps) <= EVEN_TOLERANCE * max(abs(float(steps.mean())), 1e-12))


def _label(record: dict, space) -> str:
    position = record.get(space.position_key, math.nan)
    a = f"a={record['a']:.6g} " if "a" in record else ""      # a deconvolved volume's planes have no a
    return f"{a}{space.letter}={'inf' if not math.isfinite(position) else f'{position:.6g}'} {space.symbol}"


def volume_paths(outdir: str, stem: str) -> tuple[str, str]:
    """``lfproc deconvolve``'s two files: ``OUTDIR/STEM_volume.ome.tif`` and ``OUTDIR/STEM_volume.json``."""
    import os

    base = os.path.join(outdir, stem + "_volume")
    return base + ".ome.tif", base + ".json"


#: what ``lfproc info`` calls a volume from ``lfproc deconvolve`` (recorded in the stack's description)
VOLUME_PRODUCT = "deconvolved volume"


def write_volume(outdir: str, stem: str, data: np.ndarray, voxel_um, record: dict, space) -> list[str]:
    """A deconvolved volume ``data`` (Z, Y, X) as an OME-TIFF z-stack with its voxel size in µm (planes ordered by
    ``record["z_um"]``, their records in its Description; ``space``: the object space of those depths) and
    ``record`` as ``STEM_volume.json``; both or neither (the stack is removed if the record cannot be written).
    Returns the two paths."""
    import contextlib
    import os

    from ..atomic import write_json_atomic

    stack, sidecar = volume_paths(outdir, stem)
    planes = [{"z_um": float(z), "plane": i} for i, z in enumerate(record["z_um"])]
    write_focal_stack(stack, np.asarray(data, dtype=np.float32)[..., None], planes, space, kind="ome",
                      lens_um=float(voxel_um[2]), upsample=1, product=VOLUME_PRODUCT)
    try:
        write_json_atomic(sidecar, record)
    except BaseException:
        with contextlib.suppress(OSError):      # inside an all_or_nothing group it was never renamed into place
            os.remove(stack)
        raise
    return [stack, sidecar]
