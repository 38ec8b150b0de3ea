"""The decoder cache (lfproc.decoder_cache): reuse, staleness, atomic entries, concurrency, bound, disabling.

Tiny Bayer captures (a white image of micro image disks and a textured capture, 16-bit PNGs), so each
test takes well under a second. Nothing here depends on timing.
"""

import dataclasses
import json
import os
import threading

import numpy as np
import pytest

import lfproc
from lfproc import Camera, LensGrid
from lfproc import decoder_cache as dc
from lfproc.io import write_image
from lfproc.api import DecodeSetup, prepare_decoding
from lfproc.camera import MainLens

GRID = LensGrid("hexagonal", 9.0, 0.4, (6.3, 5.8), 9, 12)
SHAPE = (84, 116)


def tiny_camera(**changes):
    cam = Camera(0.002, 0.018, 0.05, MainLens(50.0, 50.0, f_number=2.8), grid="hexagonal", cfa="GRBG", black_level=0.0, white_level=65535.0, micro_image_px=7, name="tiny")
    return dataclasses.replace(cam, **changes)


def frames(grid=GRID, seed=0, brightness=50000.0):
    """16-bit white image (anti-aliased disks on the grid) and capture (white × a random texture)."""
    yy, xx = np.mgrid[0:SHAPE[0], 0:SHAPE[1]].astype(np.float64)
    centres = grid.centers_xy_px().reshape(-1, 2)
    dist = np.min(np.hypot(xx[..., None] - centres[:, 0], yy[..., None] - centres[:, 1]), axis=-1)
    lit = np.clip(0.45 * grid.pitch_px - dist + 0.5, 0.0, 1.0)
    texture = 0.2 + 0.7 * np.random.default_rng(seed).random(SHAPE)
    return np.rint(brightness * lit).astype(np.uint16), np.rint(brightness * lit * texture).astype(np.uint16)


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A capture, its white image, a grid file recording it, and an empty cache of this test's own."""
    monkeypatch.setenv("LFPROC_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("LFPROC_NO_CACHE", raising=False)
    white, capture = frames()
    write_image(tmp_path / "white.png", white)
    write_image(tmp_path / "capture.png", capture)
    (tmp_path / "grid.json").write_text(json.dumps(dict(GRID.to_json_dict(), white_image=str(tmp_path / "white.png"))))
    return tmp_path


def decode_with_calib(folder, camera=None, **options):
    setup = prepare_decoding(camera or tiny_camera(), grid=str(folder / "grid.json"), **options, cache=True)
    return setup.decode(str(folder / "capture.png"))


def cache_entries():
    return dc.entries()


def no_derivation(monkeypatch):
    """Make deriving a decoder fail: what still decodes came from the cache."""
    def refuse(*args, **kwargs):
        raise AssertionError("the decoder was derived again instead of read from the cache")
    monkeypatch.setattr(DecodeSetup, "_make_decoder", refuse)


def test_second_decode_reuses_the_entry_and_gives_the_same_views(folder, monkeypatch):
    first = decode_with_calib(folder)
    assert len(cache_entries()) == 1
    no_derivation(monkeypatch)
    second = decode_with_calib(folder)
    assert second.views.tobytes() == first.views.tobytes()
    assert np.array_equal(second.view_mask, first.view_mask)
    assert np.allclose(second.grid.centers_xy_px(), first.grid.centers_xy_px(), rtol=0, atol=0)


def test_cached_decoder_equals_a_fresh_one_field_by_field(folder):
    """Every field of the stored decoder (arrays, grids, settings) comes back exactly (generic by field)."""
    setup = prepare_decoding(tiny_camera(), grid=str(folder / "grid.json"), cache=True)
    fresh = setup._make_decoder((), "none")
    key = setup._cache_key((), "none")
    path = os.path.join(dc.cache_dir(), key + ".lfdec")
    loaded = dc.load(path, key, type(fresh))
    assert loaded is not None
    for f in dataclasses.fields(fresh):
        a, b = getattr(fresh, f.name), getattr(loaded, f.name)
        if isinstance(a, np.ndarray):
            assert a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b), f.name
        elif isinstance(a, LensGrid):
            assert (a.kind, a.rows, a.cols) == (b.kind, b.rows, b.cols)
            assert np.array_equal(a.centers_xy_px(), b.centers_xy_px()), f.name
        else:
            assert a == b, f.name
    assert not fresh.views_delivered.all()    # zero views: stored as holes (test_zero_blocks_take_no_disk_space)


@dataclasses.dataclass(frozen=True, eq=False)
class _Entry:
    views: np.ndarray
    mask: np.ndarray
    name: str


def test_zero_blocks_take_no_disk_space_and_large_arrays_come_back_mapped(tmp_path):
    """An entry's zero views are holes (no disk space; the entry takes less than a third of the array for a
    quarter of the views set); a large array is mapped read-only from the file, a small one is an ordinary
    writable copy; both come back exactly."""
    views = np.zeros((6, 6, 64, 80, 3), np.float32)             # 61 kB per view: many file-system blocks each
    views[1:4, 2:5] = np.random.default_rng(0).random((3, 3, 64, 80, 3), dtype=np.float32)
    entry = _Entry(views, views.any(axis=(2, 3, 4)), "x")
    path = str(tmp_path / "k.lfdec")
    dc.store(path, "k", entry)
    assert dc.disk_bytes(path) < views.nbytes / 3
    loaded = dc.load(path, "k", _Entry)
    assert np.array_equal(loaded.views, views) and np.array_equal(loaded.mask, entry.mask) and loaded.name == "x"
    assert views.nbytes >= dc.MAP_BYTES and not loaded.views.flags.writeable
    assert loaded.mask.flags.writeable


def test_truncated_entry_is_not_mapped_past_its_end(tmp_path):
    views = np.ones((2, 2, 256, 256, 3), np.float32)
    path = str(tmp_path / "k.lfdec")
    dc.store(path, "k", _Entry(views, views.any(axis=(2, 3, 4)), "x"))
    with open(path, "r+b") as fh:
        fh.truncate(os.path.getsize(path) // 2)      # inside the large array
    assert dc.load(path, "k", _Entry) is None


def key_of(folder, camera=None, grid=GRID, **options):
    setup = DecodeSetup(camera or tiny_camera(), grid, None, white_path=str(folder / "white.png"), **options)
    return setup._cache_key((), "none")


@pytest.mark.parametrize("change", ["white", "camera", "grid", "m_hat", "interpolation", "demosaic", "version",
                                    "code"])
def test_every_input_of_the_state_is_in_the_key(folder, monkeypatch, change):
    before = key_of(folder)
    assert key_of(folder) == before                      # deterministic
    if change == "white":
        white, _ = frames(brightness=40000.0)
        write_image(folder / "white.png", white)
        after = key_of(folder)
    elif change == "camera":
        after = key_of(folder, tiny_camera(black_level=100.0))
    elif change == "grid":
        after = key_of(folder, grid=dataclasses.replace(GRID, origin_xy_px=(6.4, 5.8)))
    elif change == "m_hat":
        after = key_of(folder, tiny_camera(micro_image_px=5))
    elif change == "interpolation":
        after = key_of(folder, decode_interpolation="cubic")
    elif change == "demosaic":
        after = key_of(folder, demosaic="careful")
    elif change == "version":
        monkeypatch.setattr(lfproc, "__version__", lfproc.__version__ + ".post1")
        after = key_of(folder)
    else:  # the decoding code itself changed (a development checkout, same version)
        monkeypatch.setattr(dc, "_CODE_DIGEST", ["another"])
        after = key_of(folder)
    assert after != before


def test_dark_frame_is_part_of_the_key():
    args = dict(white="w", camera=tiny_camera(), grid=GRID, interpolation="linear", demosaic_method="fast")
    assert dc.decoder_key(**args) != dc.decoder_key(**args, dark="d1") != dc.decoder_key(**args, dark="d2")


def test_a_changed_white_image_is_never_served_stale(folder, monkeypatch):
    decode_with_calib(folder)
    white, _ = frames(brightness=30000.0)             # the same file name, other pixels
    write_image(folder / "white.png", white)
    changed = decode_with_calib(folder)
    assert len(cache_entries()) == 2
    monkeypatch.setenv("LFPROC_NO_CACHE", "1")
    reference = decode_with_calib(folder)
    assert changed.views.tobytes() == reference.views.tobytes()


def test_no_cache_writes_nothing_and_derives_each_time(folder, monkeypatch):
    monkeypatch.setenv("LFPROC_NO_CACHE", "1")
    assert dc.cache_dir() is None
    calls = []
    original = DecodeSetup._make_decoder
    monkeypatch.setattr(DecodeSetup, "_make_decoder", lambda self, *a: calls.append(1) or original(self, *a))
    decode_with_calib(folder)
    decode_with_calib(folder)
    assert len(calls) == 2
    assert not (folder / "cache").exists()


def test_failed_write_leaves_no_entry_and_no_temporary_file(folder, monkeypatch):
    """An error half-way through writing an entry (full disk, a bug) leaves the folder as it was; the
    decode itself goes on, with one warning."""
    def broken(array):
        blocks = dc._nonzero_blocks.__wrapped__(array)
        if blocks is not None:
            blocks.append((array.shape[0] + 5, 0))   # fails after the first blocks were written
        return blocks

    broken.__wrapped__ = dc._nonzero_blocks
    monkeypatch.setattr(dc, "_nonzero_blocks", broken)
    with pytest.warns(UserWarning, match="could not store"):
        lf = decode_with_calib(folder)
    assert np.isfinite(lf.views).all() and lf.views.any()
    left = [name for name in os.listdir(dc.cache_dir()) if not name.endswith(".lock")]
    assert left == []


def test_corrupt_or_foreign_entry_is_replaced(folder):
    setup = prepare_decoding(tiny_camera(), grid=str(folder / "grid.json"), cache=True)
    key = setup._cache_key((), "none")
    path = os.path.join(dc.cache_dir(), key + ".lfdec")
    good = open(path, "rb").read()
    open(path, "wb").write(good[: len(good) // 2])     # truncated (a disk error; never by lfproc itself)
    assert dc.load(path, key, type(setup.decoder_for((), "none"))) is None
    first = setup.decode(str(folder / "capture.png"))
    again = decode_with_calib(folder)                  # re-derived and stored whole again
    assert open(path, "rb").read() == good
    assert again.views.tobytes() == first.views.tobytes()
    assert dc.load(path, "another key", type(setup.decoder_for((), "none"))) is None


def test_concurrent_users_derive_once(folder):
    """Threads (like batch workers) asking for the same entry at once: one derives, the others read it."""
    setup = DecodeSetup(tiny_camera(), GRID, None, white_path=str(folder / "white.png"))
    key = setup._cache_key((), "none")
    builds, results = [], []
    inside = threading.Event()

    def build():
        builds.append(1)
        inside.set()
        return setup._make_decoder((), "none")

    def worker():
        results.append(dc.cached_decoder(key, build))

    first = threading.Thread(target=worker)
    first.start()
    inside.wait()                                      # the first one holds the lock and is deriving
    others = [threading.Thread(target=worker) for _ in range(3)]
    for t in others:
        t.start()
    for t in [first, *others]:
        t.join()
    assert len(builds) == 1 and len(results) == 4
    assert all(np.array_equal(r.inverse_white, results[0].inverse_white) for r in results)


def test_cache_is_bounded_least_recently_used_first(folder, monkeypatch):
    decode_with_calib(folder)
    (entry,) = cache_entries()
    size = dc.disk_bytes(entry)
    monkeypatch.setenv("LFPROC_CACHE_MAX_GB", str(1.5 * size / 1e9))
    decode_with_calib(folder, decode_interpolation="nearest")     # a second entry: the first one goes
    (left,) = cache_entries()
    assert left != entry
    assert dc.clear() == 1 and cache_entries() == []


def test_unwritable_cache_folder_warns_and_decodes(folder, monkeypatch):
    (folder / "blocked").write_text("a file where the cache folder would be")
    monkeypatch.setenv("LFPROC_CACHE_DIR", str(folder / "blocked"))
    with pytest.warns(UserWarning, match="not writable"):
        lf = decode_with_calib(folder)
    assert lf.views.any()


def test_lfproc_info_reports_and_clears_the_cache(folder):
    from conftest import run_cli

    decode_with_calib(folder)
    (entry,) = cache_entries()
    shown = run_cli("info", "--cache", "--json")
    assert shown.returncode == 0, shown.stderr
    found = json.loads(shown.stdout)
    assert found["enabled"] and found["entries"] == 1 and found["bytes"] == dc.disk_bytes(entry)
    assert found["folder"] == dc.cache_dir()
    text = run_cli("info", "--cache").stdout
    assert text.startswith(f"{dc.cache_dir()}: 1 entries")
    cleared = run_cli("info", "--clear-cache")
    assert cleared.returncode == 0 and "removed 1 entries" in cleared.stdout
    assert cache_entries() == []
