"""Fuzzing every reader and parser (issue 23): hostile input is read correctly or refused with LfprocError.

Each target starts from a valid input (tests/lytrogen.py's Lytro files, an lfproc-written TIFF/PNG/EXR,
the sample camera and scene, a calibrated grid, a decoded light field) and Hypothesis damages it: byte
level (truncations, bit flips, overwritten bytes, absurd 32-bit lengths and sizes, insertions and
deletions, biased towards the headers) and structure level (a JSON/TOML value replaced by one of
another type, a key deleted, absurd numbers). Every example must

- return, or raise :class:`lfproc.LfprocError` with a one-line message — any other exception fails;
- finish within :data:`DEADLINE_S` (a hard timer; a hang fails);
- allocate (numpy and Python, traced by tracemalloc) at most what the file's own size justifies:
  :data:`ALLOC_PER_BYTE` times its size plus :data:`ALLOC_SLACK` — declared sizes are checked before
  anything is allocated for them.

CI runs a bounded number of examples, derandomized (the same inputs every run; 7-20 s in all on a 2-core machine);
``scripts/fuzz_long.py`` runs many more with fresh randomness (LFPROC_FUZZ_EXAMPLES, LFPROC_FUZZ_RANDOM).
"""

from __future__ import annotations

import contextlib
import copy
import json
import os
import signal
import tomllib
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

import lytrogen
from conftest import SAMPLES
from lfproc import LfprocError

DEADLINE_S = 10.0
ALLOC_PER_BYTE = 64
ALLOC_SLACK = 32 << 20
#: examples per target in CI (scripts/fuzz_long.py raises it)
EXAMPLES = int(os.environ.get("LFPROC_FUZZ_EXAMPLES", "0"))
RANDOM = os.environ.get("LFPROC_FUZZ_RANDOM") == "1"
#: counts of examples run and refused per target, for scripts/fuzz_long.py's report
STATS: dict = {}


def fuzz(n_ci: int):
    # the long random runs skip shrinking (minutes per failure): the failing input is printed as found
    phases = (Phase.explicit, Phase.generate) if RANDOM else tuple(Phase)
    return settings(max_examples=EXAMPLES or 2 * n_ci, deadline=None, derandomize=not RANDOM, database=None,
                    suppress_health_check=list(HealthCheck), print_blob=True, phases=phases)


class Hang(Exception):
    """An example ran past DEADLINE_S."""


@contextlib.contextmanager
def hard_deadline(seconds: float):
    def expire(signum, frame):
        raise Hang(f"no answer within {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def read_or_refuse(target: str, read, *args, file_bytes: int | None = None):
    """Run ``read(*args)``: fine if it returns or raises a one-line LfprocError; counts the outcome."""
    counts = STATS.setdefault(target, {"tried": 0, "refused": 0})
    counts["tried"] += 1
    if file_bytes is not None:
        tracemalloc.start()
    try:
        with hard_deadline(DEADLINE_S), warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # numpy overflow or invalid value: a wrong image
            read(*args)
    except LfprocError as exc:
        counts["refused"] += 1
        assert "\n" not in str(exc)
    finally:
        if file_bytes is not None:
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
    if file_bytes is not None:
        assert peak <= ALLOC_PER_BYTE * file_bytes + ALLOC_SLACK, (peak, file_bytes)


# ----------------------------------------------------------------------------- damage
HEADER_BYTES = 600
ABSURD = [0, 1, 0x7FFFFFFF, 0xFFFFFFFF, 0x80000000, 1 << 24, 0x10000, 0xFFFF]


@st.composite
def damaged(draw, data: bytes) -> bytes:
    data = bytearray(data)
    for op in draw(st.lists(st.sampled_from(["flip", "byte", "u32", "u16", "truncate", "insert", "delete"]),
                            min_size=1, max_size=4)):
        if not data:
            break
        i = draw(st.one_of(st.integers(0, min(len(data), HEADER_BYTES) - 1), st.integers(0, len(data) - 1)))
        if op == "flip":
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "byte":
            data[i] = draw(st.integers(0, 255))
        elif op in ("u32", "u16"):
            size = 4 if op == "u32" else 2
            value = draw(st.sampled_from(ABSURD + [len(data) + 1, len(data) * 1000])) % (1 << (8 * size))
            data[i:i + size] = value.to_bytes(size, draw(st.sampled_from(["big", "little"])))
        elif op == "truncate":
            del data[i:]
        elif op == "insert":
            data[i:i] = draw(st.binary(min_size=1, max_size=16))
        else:
            del data[i:i + draw(st.integers(1, 64))]
    return bytes(data)


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(2 ** 64), 2 ** 64) | st.floats() | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=4), inner, max_size=3),
    max_leaves=4)
ABSURD_NUMBERS = [0, -1, 10 ** 9, 2 ** 31, 2 ** 63, -(2 ** 63), 10 ** 300, 1e308, float("inf"), float("nan"), 0.5]


def _slots(node, out):
    """Every (container, key) in a JSON-like tree."""
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        out.append((node, key))
        _slots(value, out)
    return out


@st.composite
def altered(draw, document):
    """A copy of a JSON/TOML tree with 1-3 values replaced (another type, an absurd number) or keys deleted."""
    document = copy.deepcopy(document)
    for _ in range(draw(st.integers(1, 3))):
        slots = _slots(document, [])
        if not slots:
            break
        parent, key = draw(st.sampled_from(slots))
        op = draw(st.sampled_from(["replace", "delete", "absurd"]))
        if op == "delete":
            del parent[key]
        elif op == "absurd":
            parent[key] = draw(st.sampled_from(ABSURD_NUMBERS))
        else:
            parent[key] = draw(JSON_VALUES)
    return document


def toml_text(table: dict) -> str:
    """A minimal TOML writer for the trees above (strings, numbers, booleans, arrays, tables)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float):
            return "nan" if v != v else ("inf" if v > 0 else "-inf") if v in (float("inf"), float("-inf")) else repr(v)
        if isinstance(v, int):
            return str(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{json.dumps(str(k))} = {value(x)}" for k, x in v.items() if x is not None) + "}"
        return '""'
    return "\n".join(f"{json.dumps(str(k))} = {value(v)}" for k, v in table.items() if v is not None) + "\n"


# ----------------------------------------------------------------------------- Lytro
DN = np.arange(8 * 6).reshape(6, 8) * 20 % 1000 + 10
ILLUM = lytrogen.illum_document(8, 6, modulation=False)
GOOD_CONTAINER = lytrogen.container_bytes(lytrogen.pack10_little(DN), *lytrogen.frame_metadata_of(ILLUM))
F01 = lytrogen.f01_metadata(6, 4)
F01_RAW = lytrogen.pack12_big(np.full((4, 6), 1000))


def _read_lytro(path):
    from lfproc.io import read_lytro, read_lytro_metadata
    read_lytro_metadata(path)
    capture, _ = read_lytro(path)
    assert np.all(np.isfinite(capture.data))  # read correctly: never a NaN or infinite image


@fuzz(60)
@given(data=damaged(GOOD_CONTAINER))
def test_lytro_containers_with_damaged_bytes(data, tmp_path_factory):
    path = tmp_path_factory.mktemp("lfr") / "IMG.LFR"
    path.write_bytes(data)
    read_or_refuse("lytro container (bytes)", _read_lytro, path, file_bytes=len(data))


@fuzz(60)
@given(metadata=altered(lytrogen.frame_metadata_of(ILLUM)[0]), private=altered(lytrogen.frame_metadata_of(ILLUM)[1]))
def test_lytro_containers_with_altered_metadata(metadata, private, tmp_path_factory):
    data = lytrogen.container_bytes(lytrogen.pack10_little(DN), metadata, private)
    path = tmp_path_factory.mktemp("lfr") / "IMG.LFR"
    path.write_bytes(data)
    read_or_refuse("lytro container (metadata)", _read_lytro, path, file_bytes=len(data))


@fuzz(60)
@given(document=altered(F01), raw=st.one_of(st.just(F01_RAW), damaged(F01_RAW)))
def test_lytro_raw_pairs(document, raw, tmp_path_factory):
    folder = tmp_path_factory.mktemp("raw")
    (folder / "frame.RAW").write_bytes(raw)
    (folder / "frame.json").write_text(json.dumps(document))
    read_or_refuse("lytro raw + metadata", _read_lytro, folder / "frame.RAW",
                   file_bytes=len(raw) + (folder / "frame.json").stat().st_size)


@fuzz(30)
@given(text=damaged(json.dumps(lytrogen.illum_document(8, 6), indent="\t").encode()))
def test_lytro_metadata_text_damaged(text, tmp_path_factory):
    folder = tmp_path_factory.mktemp("raw")
    (folder / "frame.RAW").write_bytes(lytrogen.pack10_little(DN))
    (folder / "frame.TXT").write_bytes(text)
    read_or_refuse("lytro metadata text", _read_lytro, folder / "frame.RAW", file_bytes=len(text) + 60)


# ----------------------------------------------------------------------------- images
def _image_bytes(extension: str, dtype) -> bytes:
    import tempfile

    from lfproc.io import write_image

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"image{extension}"
        image = (np.arange(12 * 16).reshape(12, 16) / 200.0).astype(np.float32)
        write_image(path, (image * 65535).astype(np.uint16) if dtype == np.uint16 else image)
        return path.read_bytes()


IMAGES = {ext: _image_bytes(ext, dtype) for ext, dtype in ((".tif", np.float32), (".png", np.uint16),
                                                            (".exr", np.float32))}


def _read_image(path):
    from lfproc.io import read_capture, read_image, read_metadata
    assert np.all(np.isfinite(read_capture(path).data))
    read_image(path)
    read_metadata(path)


@pytest.mark.parametrize("extension", sorted(IMAGES))
def test_image_headers(extension, tmp_path_factory):
    @fuzz(40)
    @given(data=damaged(IMAGES[extension]))
    def check(data):
        path = tmp_path_factory.mktemp("img") / f"capture{extension}"
        path.write_bytes(data)
        read_or_refuse(f"image {extension}", _read_image, path, file_bytes=len(data))
    check()


# ----------------------------------------------------------------------------- camera, scene, grid
CAMERA_TEXT = (SAMPLES / "cameras" / "paper-f100.toml").read_text()
SCENE_TEXT = (SAMPLES / "sample" / "scene.toml").read_text()


def _camera(text):
    from lfproc.camera import Camera
    Camera.from_toml_string(text, source="fuzz.toml")


@fuzz(80)
@given(table=altered(tomllib.loads(CAMERA_TEXT)))
def test_camera_files_with_altered_values(table):
    read_or_refuse("camera TOML (values)", _camera, _nested_toml(table))


@fuzz(40)
@given(text=damaged(CAMERA_TEXT.encode()))
def test_camera_files_with_damaged_text(text):
    read_or_refuse("camera TOML (text)", _camera, text.decode("utf-8", "replace"))


def _nested_toml(table: dict, prefix: str = "") -> str:
    """TOML with one [section] per nested table (array of tables as [[name]])."""
    scalars = {k: v for k, v in table.items() if not isinstance(v, dict) and not
               (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))}
    out = [toml_text(scalars)] if scalars else []
    for key, value in table.items():
        name = f"{prefix}{json.dumps(str(key))}"
        if isinstance(value, dict):
            out.append(f"[{name}]\n" + _nested_toml(value, name + "."))
        elif isinstance(value, list) and value and all(isinstance(x, dict) for x in value):
            out += [f"[[{name}]]\n" + toml_text(x) for x in value]
    return "\n".join(out)


def _scene(text, folder):
    from lfproc.simulate import load_scene_file
    path = folder / "scene.toml"
    path.write_text(text)
    load_scene_file(path)


@fuzz(60)
@given(table=altered(tomllib.loads(SCENE_TEXT)))
def test_scene_files_with_altered_values(table, tmp_path_factory):
    read_or_refuse("scene TOML (values)", _scene, _nested_toml(table), tmp_path_factory.mktemp("scene"))


@fuzz(30)
@given(text=damaged(SCENE_TEXT.encode()))
def test_scene_files_with_damaged_text(text, tmp_path_factory):
    read_or_refuse("scene TOML (text)", _scene, text.decode("utf-8", "replace"), tmp_path_factory.mktemp("scene"))


def _grid_document():
    from lfproc import LensGrid
    return dict(LensGrid("hexagonal", 10.5, 0.3, (5.2, 4.9), 12, 14).to_json_dict(), white_image="white.png")


def _grid(path):
    from lfproc import LensGrid
    LensGrid.load(path)


@fuzz(60)
@given(document=altered(_grid_document()))
def test_grid_files_with_altered_values(document, tmp_path_factory):
    path = tmp_path_factory.mktemp("grid") / "grid.json"
    path.write_text(json.dumps(document))
    read_or_refuse("grid JSON", _grid, path, file_bytes=path.stat().st_size)


# ----------------------------------------------------------------------------- light field files
def _read_lightfield(path):
    from lfproc import LightField
    LightField.read_camera(path)
    LightField.load(path)


MEMBER_VALUES = st.one_of(
    st.builds(lambda shape, dtype: np.zeros(shape, dtype),
              st.lists(st.integers(0, 4), min_size=0, max_size=6).map(tuple),
              st.sampled_from(["f4", "f8", "u1", "i8", "c8", "U3", "?"])),
    st.just(np.array(["x", None], dtype=object)),
    st.text(max_size=20).map(np.array))


@fuzz(60)
@given(members=st.dictionaries(st.sampled_from(["views", "camera_toml", "grid_json", "view_mask", "format"]),
                               MEMBER_VALUES, max_size=5), keep_format=st.booleans())
def test_lightfield_files_with_wrong_members(members, keep_format, tmp_path_factory):
    path = tmp_path_factory.mktemp("lf") / "lf.lfp.npz"
    if keep_format:
        members["format"] = np.array("lfproc-lightfield-1")
    with open(path, "wb") as fh:
        np.savez(fh, **members)  # object arrays are pickled in the file: the reader must never unpickle them
    read_or_refuse("light field .lfp.npz (members)", _read_lightfield, path, file_bytes=path.stat().st_size)


@pytest.fixture(scope="module")
def lightfield_file(tmp_path_factory):
    from lfproc import LensGrid, LightField
    from lfproc.camera import Camera

    camera = Camera.from_toml_string(CAMERA_TEXT, source="cam")
    m = camera.m_hat
    views = np.linspace(0, 1, m * m * 3 * 4).reshape(m, m, 3, 4, 1).astype(np.float32)
    path = tmp_path_factory.mktemp("lf") / "lf.lfp.npz"
    LightField(views, camera, LensGrid("rectangular", float(m), 0.0, (1.0, 1.0), 3, 4)).save(path)
    return path.read_bytes()


def test_lightfield_files_with_damaged_bytes(lightfield_file, tmp_path_factory):
    @fuzz(60)
    @given(data=damaged(lightfield_file))
    def check(data):
        path = tmp_path_factory.mktemp("lf") / "lf.lfp.npz"
        path.write_bytes(data)
        read_or_refuse("light field .lfp.npz (bytes)", _read_lightfield, path, file_bytes=len(data))
    check()


# ----------------------------------------------------------------------------- absurd declared sizes, explicitly
def _tiff_declaring(width: int, height: int) -> bytes:
    """A little-endian TIFF header declaring a ``width`` x ``height`` float32 image, with 64 bytes of data."""
    import struct

    tags = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 32), (259, 3, 1, 1), (262, 3, 1, 1),
            (273, 4, 1, 8 + 2 + 12 * 11 + 4), (277, 3, 1, 1), (278, 4, 1, height), (279, 4, 1, 64),
            (284, 3, 1, 1), (339, 3, 1, 3)]
    ifd = struct.pack("<H", len(tags)) + b"".join(struct.pack("<HHII", *t) for t in tags) + struct.pack("<I", 0)
    return b"II*\x00" + struct.pack("<I", 8) + ifd + bytes(64)


def test_an_image_header_declaring_gigabytes_is_refused_before_allocating(tmp_path):
    path = tmp_path / "huge.tif"
    path.write_bytes(_tiff_declaring(60000, 60000))  # 14.4 GB of float pixels declared in 226 bytes
    from lfproc.io import read_capture
    tracemalloc.start()
    try:
        with pytest.raises(LfprocError, match="huge.tif: .*(cannot hold|corrupt)"):
            read_capture(path)
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < ALLOC_SLACK
    small = tmp_path / "small.tif"
    small.write_bytes(_tiff_declaring(4, 4))  # the same header with a size its data holds reads fine
    assert read_capture(small).data.shape == (4, 4)


def test_a_lightfield_member_declaring_gigabytes_is_refused_before_allocating(tmp_path):
    import zipfile

    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (100000, 100000), }"
    header = header + " " * (-(10 + len(header) + 1) % 64) + "\n"
    npy = b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + bytes(64)
    path = tmp_path / "lf.lfp.npz"
    with zipfile.ZipFile(path, "w") as archive:
        for name, value in (("format", np.array("lfproc-lightfield-1")), ("camera_toml", np.array("")),
                            ("grid_json", np.array(""))):
            with archive.open(name + ".npy", "w") as fh:
                np.lib.format.write_array(fh, value)
        archive.writestr("views.npy", npy)
    from lfproc import LightField
    tracemalloc.start()
    try:
        with pytest.raises(LfprocError, match="declares"):
            LightField.load(path)
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < ALLOC_SLACK


def test_an_object_member_is_refused_without_unpickling(tmp_path):
    import pickle

    class Boom:
        def __reduce__(self):
            return (os.system, ("touch " + str(tmp_path / "unpickled"),))

    path = tmp_path / "lf.lfp.npz"
    np.savez(path, views=np.array([Boom()], dtype=object), camera_toml=np.array(""), grid_json=np.array(""),
             format=np.array("lfproc-lightfield-1"))
    from lfproc import LightField
    with pytest.raises(LfprocError, match="never unpickles"):
        LightField.load(path)
    assert not (tmp_path / "unpickled").exists()
    del pickle


def test_lytro_metadata_declaring_a_huge_sensor_is_refused_before_allocating(tmp_path):
    document = copy.deepcopy(F01)
    document["image"]["width"], document["image"]["height"] = 200000, 100000
    (tmp_path / "frame.RAW").write_bytes(F01_RAW)
    (tmp_path / "frame.json").write_text(json.dumps(document))
    tracemalloc.start()
    try:
        with pytest.raises(LfprocError):
            _read_lytro(tmp_path / "frame.RAW")
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    assert peak < ALLOC_SLACK


# ----------------------------------------------------------------------------- the batch manifest and journal
def _manifest_document():
    return {"version": 1, "parameters": {"views": True},
            "captures": {"/data/cap0.png": {"status": "done", "last_run": "done", "fingerprint": "f0",
                                            "parameters": {}, "outputs": ["cap0_a+0.000.tif"], "error": None,
                                            "seconds": 1.0}},
            "summary": {"done": 1}}


def _resume(folder):
    from lfproc import batch

    manifest = batch.Manifest(str(folder), {"views": True})
    job = batch.Job("/data/cap0.png", "cap0", str(folder), "", None, None, (0.0,), False)
    if manifest.is_complete(job, "f0"):
        manifest.record(job, batch.JobResult(job.source, "skipped"), "f0")
    manifest.record(job, batch.JobResult(job.source, "done", (str(folder / "cap0_a+0.000.tif"),)), "f0")
    manifest.save({"done": 1})


@fuzz(60)
@given(document=altered(_manifest_document()), journal=damaged(
    (json.dumps(["/data/cap0.png", _manifest_document()["captures"]["/data/cap0.png"]]) + "\n").encode() * 2))
def test_batch_manifests_and_journals(document, journal, tmp_path_factory):
    folder = tmp_path_factory.mktemp("out")
    (folder / "lfproc-manifest.json").write_text(json.dumps(document))
    (folder / ".lfproc-manifest.journal").write_bytes(journal)
    (folder / "cap0_a+0.000.tif").write_bytes(b"x")
    (folder / "cap0_a+0.000.json").write_bytes(b"{}")
    read_or_refuse("batch manifest + journal", _resume, folder)


# ----------------------------------------------------------------------------- escapes the long runs found
@pytest.mark.parametrize("change, key", [({"bitsPerPixel": 2 ** 62}, "bitsPerPixel"),   # 2 ** bits: a hang
                                         ({"mosaic": 7}, "Bayer"),                    # AttributeError
                                         ({"black": float("nan")}, "black"),          # a NaN image
                                         ({"height": 10 ** 300}, "sensor size")])      # OverflowError
def test_lytro_metadata_escapes_found_by_fuzzing(change, key, tmp_path):
    metadata, private = copy.deepcopy(lytrogen.frame_metadata_of(ILLUM))
    raw = metadata["image"]["rawDetails"]
    if "bitsPerPixel" in change:
        raw["pixelPacking"]["bitsPerPixel"] = change["bitsPerPixel"]
    elif "mosaic" in change:
        raw["mosaic"] = change["mosaic"]
    elif "height" in change:
        metadata["image"]["height"] = change["height"]
    else:
        raw["pixelFormat"]["black"] = change["black"]
    path = tmp_path / "IMG.LFR"
    path.write_bytes(lytrogen.container_bytes(lytrogen.pack10_little(DN), metadata, private))
    with hard_deadline(DEADLINE_S), pytest.raises(LfprocError, match=key):
        _read_lytro(path)


def test_a_grid_origin_of_the_wrong_length_is_refused(tmp_path):
    """Found by scripts/fuzz_long.py: origin_xy_px with one number raised IndexError."""
    document = dict(_grid_document(), origin_xy_px=[5.0])
    path = tmp_path / "grid.json"
    path.write_text(json.dumps(document))
    with pytest.raises(LfprocError, match="origin_xy_px"):
        _grid(path)


def test_a_scene_texture_that_is_not_a_name_is_refused(tmp_path):
    """Found by scripts/fuzz_long.py: texture = [ ... ] raised TypeError (unhashable list)."""
    table = tomllib.loads(SCENE_TEXT)
    table["plane"][0]["texture"] = ["noise"]
    with pytest.raises(LfprocError, match="texture"):
        _scene(_nested_toml(table), tmp_path)


def test_a_lightfield_grid_member_that_is_not_json_is_refused(tmp_path):
    """Found by scripts/fuzz_long.py: a grid_json member that is not JSON raised JSONDecodeError."""
    path = tmp_path / "lf.lfp.npz"
    np.savez(path, views=np.zeros((3, 3, 2, 2, 1), np.float32), camera_toml=np.array(""),
             grid_json=np.array("{not json"), format=np.array("lfproc-lightfield-1"))
    from lfproc import LightField
    with pytest.raises(LfprocError, match="grid_json"):
        LightField.load(path)


def test_lightfield_views_that_are_not_numbers_are_refused(tmp_path):
    """Found by scripts/fuzz_long.py: views of strings raised ValueError in the float conversion."""
    path = tmp_path / "lf.lfp.npz"
    np.savez(path, views=np.array("abc"), camera_toml=np.array(""), grid_json=np.array(""),
             format=np.array("lfproc-lightfield-1"))
    from lfproc import LightField
    with pytest.raises(LfprocError, match="not numbers"):
        LightField.load(path)


def test_a_camera_whose_pitch_ratio_overflows_is_refused():
    """Found by scripts/fuzz_long.py: pitch_mm 1e308 over pixel_pitch_mm 0.01 raised OverflowError."""
    table = tomllib.loads(CAMERA_TEXT)
    table["mla"]["pitch_mm"] = 1e308
    table.setdefault("decode", {})["micro_image_px"] = 4
    with pytest.raises(LfprocError, match="finite"):
        _camera(_nested_toml(table))


# ----------------------------------------------------------------------------- truncated TIFFs: no stderr leaks
def _truncated_tiffs(folder: Path) -> list[Path]:
    """TIFFs as cameras and microscopes write them (8 and 16 bits, raw and deflate strips of 8 rows), cut
    at 40 points from the header through the IFD into the strips, and with a strip offset or byte count
    pointing past the end of the file (issue 30: libtiff printed "Unexpected end of file" on a second line)."""
    import tifffile

    paths = []
    for dtype in (np.uint8, np.uint16):
        image = (np.arange(64 * 96).reshape(64, 96) % 200).astype(dtype)
        for compression in (None, "zlib"):
            base = folder / "base.tif"
            tifffile.imwrite(base, image, rowsperstrip=8, compression=compression)
            data = base.read_bytes()
            with tifffile.TiffFile(base) as tif:
                page = tif.pages[0]
                ifd, tags = page.offset, {tag.code: tag for tag in page.tags.values()}
            cuts = sorted({*range(0, len(data), max(1, len(data) // 40)), ifd + 1, ifd + 2 + 12 * 4 + 5,
                           page.dataoffsets[len(page.dataoffsets) // 2] + 10, page.dataoffsets[-1] + 3})
            variants = {f"cut{cut}": data[:cut] for cut in cuts}
            for code in (273, 279):      # StripOffsets, StripByteCounts: the first one far past the end
                damaged_bytes = bytearray(data)
                at, size = tags[code].valueoffset, (4 if tags[code].dtype in (4, 16) else 2)
                damaged_bytes[at:at + size] = min(3 * len(data), (1 << (8 * size)) - 1).to_bytes(size, "little")
                variants[f"tag{code}"] = bytes(damaged_bytes)
            for name, content in variants.items():
                path = folder / f"{dtype.__name__}-{compression}-{name}.tif"
                path.write_bytes(content)
                paths.append(path)
    return paths


def test_truncated_tiffs_are_refused_without_a_word_from_third_party_libraries(tmp_path, capfd):
    """Every reader (and lfproc info's description, the inputs' header probe) on each damaged TIFF: returns
    or raises a one-line LfprocError, and nothing reaches the process's stderr (file descriptor 2, where C
    libraries write) — the command's own error line is the only one."""
    from lfproc.inputs import probe_image
    from lfproc.io import describe_file

    paths = _truncated_tiffs(tmp_path)
    assert len(paths) >= 150
    for path in paths:
        for read in (describe_file, probe_image, _read_image):
            read_or_refuse("truncated TIFF", read, path)
        leaked = capfd.readouterr().err
        assert leaked == "", (path.name, leaked)


def test_a_truncated_tiff_is_one_line_from_the_command(tmp_path):
    """The same files through the command line: exit 2 and exactly one line on stderr."""
    from conftest import assert_clean_error, run_cli

    paths = {p.name: p for p in _truncated_tiffs(tmp_path)}
    camera = SAMPLES / "sample" / "camera.toml"
    names = [name for name in paths if name.startswith("uint8-None-tag273") or name.startswith("uint16-zlib-cut")]
    for name in names[:1] + names[-2:]:
        proc = run_cli("calibrate", paths[name], "--camera", camera, "-o", tmp_path / "grid.json")
        assert_clean_error(proc, str(paths[name]))
