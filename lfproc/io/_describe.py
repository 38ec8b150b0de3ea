"""What a file is and holds (``lfproc info``): Lytro containers and raw pairs, camera raws, images.

The dict has the contract's keys (``ARCHITECTURE.md``, "lfproc info"): ``format``
(``"lytro-container"``, ``"lytro-raw"``, ``"camera-raw"``, ``"image"``, ``"lfproc-output"`` for an
image lfproc wrote, with its ``product`` and embedded ``tags``: a data product, a preview picture with
``preview_of``, or a focal z-stack, ``_describe_stack.py``), ``raw_light_field``,
``width``, ``height``, and for Lytro files ``camera_model`` and ``sections``; plus what else each
kind of file tells (serial, bit depth, CFA, levels, lens and micro lens data).
"""

from __future__ import annotations

import math
import os

from ..errors import LfprocError
from ._checks import _NotThisFormat, existing_file, library_error, one_line, unreadable_reasons
from ._native import libraries_quiet


def describe_file(path: str | os.PathLike) -> dict:
    """Describe any capture or image file without decoding it.

    Raises
    ------
    LfprocError
        Missing, empty or unreadable files (a corrupt Lytro container is described, its bad sections
        marked ``"sha1_ok": false``, as long as its structure can be parsed).
    """
    from ._lytro_read import is_lytro_file
    from ._read import RAW_EXTENSIONS

    from ..lightfield import is_lightfield_file

    path = existing_file(path)
    if is_lytro_file(path):
        return _describe_lytro(path)
    if is_lightfield_file(path):
        return _describe_lightfield(path)
    _refuse_json(path)
    order = (_describe_camera_raw, _describe_image)
    if os.path.splitext(path)[1].lower() not in RAW_EXTENSIONS:
        order = order[::-1]
    reasons = []
    for describe in order:
        try:
            return describe(path)
        except _NotThisFormat as exc:
            reasons.append(str(exc))
    raise LfprocError(f"{path}: not a readable image, camera raw or Lytro file{unreadable_reasons(reasons)}; "
                      f"pass a capture or image file")


def _refuse_json(path: str) -> None:
    """A JSON file is no image: say which of lfproc's JSON files it is, and what reads it."""
    import json

    with open(path, "rb") as fh:
        if not fh.read(64).lstrip().startswith(b"{"):
            return
    from ._napari_metadata import is_napari_metadata

    stem = os.path.splitext(path)[0]
    raw = next((stem + ext for ext in (".raw", ".RAW") if os.path.isfile(stem + ext)), None)
    try:
        with open(path, encoding="utf-8") as fh:
            document = json.load(fh)
    except (OSError, ValueError, UnicodeDecodeError):
        document = None
    if raw is not None:
        what = f" (the metadata of the Lytro raw {raw}: pass that)"
    elif is_napari_metadata(path):
        what = " (napari-LF's metadata of a microscope: `lfproc.read_camera(path) reads it as a camera`)"
    elif isinstance(document, dict) and "pitch_px" in document:
        what = " (`a lens grid, the file lfproc.calibrate_white(...).save(path) writes: pass it as grid=`)"
    elif isinstance(document, dict) and ("provenance" in document or "source" in document):
        what = " (the sidecar of an output lfproc wrote: the metadata of the image beside it, readable as it is)"
    else:
        what = ""
    raise LfprocError(f"{path}: a JSON file{what}, not an image; pass a capture or image file")


def _describe_lytro(path: str) -> dict:
    from ._lytro_container import has_container_extension, is_container, picture_kind, read_container
    from ._lytro_read import metadata_sibling, open_lytro

    info = {"path": path}
    if has_container_extension(path) or is_container(path):
        container = read_container(path, verify=False)
        info.update(format="lytro-container", sections=_sections(container))
        try:
            lytro = open_lytro(path, verify=False)
        except LfprocError as exc:
            if "holds no raw light field" not in str(exc):
                stripped = _without_image(container, info)
                if stripped is None:
                    raise
                return stripped
            info.update(raw_light_field=False, content=picture_kind(container.toc), width=None, height=None,
                        camera_model=None)
            from ._describe_picture import describe_picture
            try:
                info.update(describe_picture(container))
            except LfprocError as exc:     # a picture of a kind lfproc does not read: described as far as it can
                info["picture_note"] = str(exc)
            return info
    else:
        lytro = open_lytro(path, pixels=False, check_size=False)
        info.update(format="lytro-raw", metadata_file=metadata_sibling(path), sections=[])
    info.update(_metadata_fields(lytro.metadata))
    if info["format"] == "lytro-raw":
        size = os.path.getsize(path)
        info["size_matches_metadata"] = size == lytro.metadata.packed_bytes
    info["raw_light_field"] = all(s["sha1_ok"] for s in info["sections"]) and info.get("size_matches_metadata", True)
    return info


def _without_image(container, info: dict) -> dict | None:
    """A container whose raw image section is absent but whose frame metadata is present (e.g. ExifTool's
    test file, its 16 MB image removed): its metadata described, no raw light field, the image "missing"."""
    from ._lytro_container import frame_without_image
    from ._lytro_metadata import parse_metadata

    found = frame_without_image(container)
    if found is None:
        return None
    frame, reference = found
    info.update(_metadata_fields(parse_metadata(frame.metadata, frame.private, container.path,
                                                frame.modulation_frame)))
    info.update(raw_light_field=False, raw_frame=f"missing: the raw image section {reference} named by the table "
                f"of contents is not in the file (removed or an incomplete copy); the metadata is intact",
                content="Lytro frame metadata without its raw image")
    return info


def _metadata_fields(meta) -> dict:
    black, white = meta.levels()

    def mm(metres):
        return None if metres is None else metres * 1e3

    exit_pupil = math.inf if meta.exit_pupil_at_infinity else mm(meta.exit_pupil_offset_m)
    return {
        "camera_model": meta.model, "serial": meta.serial, "width": meta.width, "height": meta.height,
        "bits_per_pixel": meta.bits_per_pixel, "endianness": meta.endianness, "cfa": meta.cfa,
        "black_level": black.tolist(), "white_level": white.tolist(),
        "modulation_frame": meta.modulation_frame,
        "lens": {"focal_length_mm": mm(meta.focal_length_m), "f_number": meta.f_number,
                 "exit_pupil_distance_mm": exit_pupil, "zoom_step": meta.zoom_step, "focus_step": meta.focus_step,
                 "infinity_lambda": meta.infinity_lambda},
        "sensor": {"pixel_pitch_mm": mm(meta.pixel_pitch_m)},
        "mla": {"pitch_mm": mm(meta.lens_pitch_m), "tiling": meta.tiling,
                "rotation_deg": None if meta.rotation_rad is None else math.degrees(meta.rotation_rad),
                "sensor_offset_mm": None if meta.sensor_offset_m is None else [v * 1e3 for v in meta.sensor_offset_m]},
    }


def _sections(container) -> list[dict]:
    roles = {}
    _collect_references(container.toc, "", roles)
    out = []
    for section in container.sections:
        data = bytes(container.data[section.offset:section.offset + min(section.length, 4)])
        if section.kind == "LFM":
            content = "table of contents (JSON)"
        elif section.sha1.lower() in roles:
            content = roles[section.sha1.lower()]
        elif data.startswith(b"\xff\xd8"):
            content = "JPEG image"
        elif data.lstrip().startswith(b"{"):
            content = "JSON"
        else:
            content = "data"
        out.append({"kind": section.kind, "length": section.length, "sha1": section.sha1,
                    "sha1_ok": section.sha1_ok, "content": content})
    return out


_ROLE_NAMES = {"imageRef": "image", "metadataRef": "frame metadata (JSON)",
               "privateMetadataRef": "private metadata (JSON: serial numbers)"}


def _collect_references(node, where: str, roles: dict) -> None:
    """Map each ``sha1-…`` reference in the table of contents to what refers to it."""
    if isinstance(node, dict):
        for key, value in node.items():
            if isinstance(value, str) and value.lower().startswith("blob:"):
                value = value[5:]
            if isinstance(value, str) and value.lower().startswith("sha1-") and key.endswith(("Ref", "Url")):
                role = _ROLE_NAMES.get(key, key[:-3])
                if key in ("imageRef", "imageUrl"):
                    raw = "frameArray" in where or where.startswith("frames")
                    role = "raw sensor image (packed)" if raw else f"image ({where or 'picture'})"
                roles.setdefault(value.lower(), role)
            else:
                _collect_references(value, f"{where}.{key}" if where else key, roles)
    elif isinstance(node, list):
        for item in node:
            _collect_references(item, where, roles)


def _describe_lightfield(path: str) -> dict:
    """A light field written by ``lfproc decode``: its views' shape from the array header (nothing loaded)."""
    import zipfile

    import numpy as np

    try:
        with zipfile.ZipFile(path) as archive, archive.open("views.npy") as member:
            version = np.lib.format.read_magic(member)
            read_header = np.lib.format.read_array_header_1_0 if version == (1, 0) else \
                np.lib.format.read_array_header_2_0
            shape, _, dtype = read_header(member)
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as exc:
        raise LfprocError(f"{path}: not a readable light field file ({exc}); decode the capture again") from None
    m, _, rows, cols, channels = shape if len(shape) == 5 else (None,) * 5
    return {"path": path, "format": "lightfield", "raw_light_field": False, "decoded_light_field": True,
            "width": cols, "height": rows, "views": m, "channels": channels, "dtype": str(dtype)}


def _describe_camera_raw(path: str) -> dict:
    import rawpy

    try:
        with libraries_quiet(), rawpy.imread(path) as raw:
            height, width = raw.raw_image_visible.shape
            white = float(raw.white_level)
            info = {"path": path, "format": "camera-raw", "raw_light_field": True, "width": int(width),
                    "height": int(height), "black_level": [float(v) for v in raw.black_level_per_channel],
                    "white_level": white, "bits_per_pixel": int(math.ceil(math.log2(white + 1))),
                    "colour_channels": raw.color_desc.decode("ascii", "replace")[:int(raw.num_colors)]}
    except rawpy.LibRawFileUnsupportedError:
        raise _NotThisFormat("LibRaw: not a supported camera raw") from None
    except rawpy.LibRawError as exc:
        from ._libraw import _libraw_message
        from ._read import RAW_EXTENSIONS

        if os.path.splitext(path)[1].lower() not in RAW_EXTENSIONS:
            raise _NotThisFormat(f"LibRaw: {_libraw_message(exc)}") from None
        raise LfprocError(f"{path}: truncated or corrupt camera raw ({_libraw_message(exc)}); re-copy the file") \
            from None
    return info


def _describe_image(path: str) -> dict:
    import OpenImageIO as oiio

    with libraries_quiet() as native:
        inp = oiio.ImageInput.open(path)
    if inp is None:
        raise _NotThisFormat(library_error(oiio.geterror) or one_line(native.text()) or "OpenImageIO: unknown format")
    try:
        spec = inp.spec()
        info = {"path": path, "format": "image", "file_format": inp.format_name(),
                "raw_light_field": True, "width": spec.width, "height": spec.height,
                "channels": spec.nchannels, "channel_names": list(spec.channelnames),
                "pixel_type": str(spec.format), "bits_per_pixel": spec.format.size() * 8}
        tags = _lfproc_tags(spec, _description(spec, info["file_format"], path))
        stack_header = info["file_format"] == "tiff" and _is_stack_header(spec)
    finally:
        inp.close()
    if stack_header:          # a z-stack lfproc wrote (refocus --stack): tifffile reads its structure
        from ._describe_stack import describe_stack

        stack = describe_stack(path)
        if stack is not None:
            return stack
    if tags is None:         # embedded tags gone (an image re-saved by another program): lfproc's sidecar tells
        tags = _sidecar_tags(path)
    product = None if tags is None else lfproc_product(tags)
    if product is not None:   # a data product or a picture of one: no raw light field any more
        info.update(format="lfproc-output", product=product, raw_light_field=False)
        if "preview" in tags:
            info["preview_of"] = tags["preview"]
    if tags:
        info["tags"] = tags
    return info


def _is_stack_header(spec) -> bool:
    from ._describe_stack import is_stack_header

    try:
        return is_stack_header(spec.get_string_attribute("ImageDescription") or "")
    except UnicodeDecodeError:
        return False


def _description(spec, file_format: str, path: str) -> str:
    """An image's ``ImageDescription``; a GIF's comment read whole by Pillow (OpenImageIO keeps only the last
    255-byte block of a longer comment, and lfproc's tags name their source's path)."""
    if file_format == "gif":
        from PIL import Image

        try:
            with Image.open(path) as image:
                return image.info.get("comment", b"").decode("utf-8", "replace")
        except (OSError, ValueError, EOFError, SyntaxError):  # what OpenImageIO read is all there is
            pass
    return spec.get_string_attribute("ImageDescription")


def _lfproc_tags(spec, description: str) -> dict | None:
    """The metadata lfproc embedded in an image it wrote (``Software`` "lfproc", JSON in its
    ``description``; a GIF, which has no Software tag, says ``"software": "lfproc"`` in its JSON comment), or
    None for any other image."""
    import json

    software = spec.get_string_attribute("Software")
    if software not in ("lfproc", ""):
        return None
    try:
        tags = json.loads(description or "{}")
    except (ValueError, UnicodeDecodeError):
        return None
    if not isinstance(tags, dict) or (software != "lfproc" and tags.pop("software", None) != "lfproc"):
        return None
    return tags


def _sidecar_tags(path: str) -> dict | None:
    """The sidecar ``NAME.json`` beside an image, when it is one lfproc wrote for an exported Lytro picture's
    image (``source``, ``kind`` and ``lambda``), else None."""
    import json

    stem, extension = os.path.splitext(path)
    try:
        with open(stem + ".json", encoding="utf-8") as fh:
            tags = json.load(fh)
    except (OSError, ValueError):
        return None
    if extension.lower() == ".json" or not isinstance(tags, dict) or not _is_picture_export(tags):
        return None
    return tags


def _is_picture_export(tags: dict) -> bool:
    return {"source", "kind", "lambda"} <= set(tags)


def lfproc_product(tags: dict) -> str | None:
    """What an lfproc data product is, from its embedded tags (a refocused slice, a view, a view mosaic, a
    depth map, a preview picture of one of these, an image exported from a processed Lytro picture); None for
    anything else lfproc wrote (a simulated capture or white image is still a capture)."""
    if _is_picture_export(tags):
        return f"image of a processed Lytro picture ({tags['kind']}), exported by `lfproc.outputs.export_picture`"
    if "preview" in tags:
        return "preview picture"
    if "a" in tags:
        return "refocused slice"
    if "view" in tags:
        return "view"
    if "views_per_side" in tags:
        return "view mosaic"
    if "unit" in tags:
        return "depth map"
    return None
