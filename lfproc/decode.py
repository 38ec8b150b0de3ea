"""Decoding: resample a sensor image along the fitted lens lattice into m̂ × m̂ views (paper Section 5.1).

Real captures rarely have an odd, integer number of pixels per micro lens, or a lattice aligned with
the pixel rows. The paper resamples the raw image so every micro image is m̂ × m̂ pixels with m̂ odd
(9 µm pixels under 250 µm lenses → m̂ = 25 at an effective pitch of 10 µm). Here that is one
vectorised pass of ``cv2.remap``:

* **Sample positions.** View (ky, kx) of lens (r, q) is read at the lens centre plus
  ``(kx − c)·s·u + (ky − c)·s·v`` sensor pixels, with s = pitch_px / m̂ the effective pixel in sensor
  pixels and (u, v) the lattice axes: rotation is removed and every micro image is centred on its
  lens. The map is laid out as ``(ky, kx, r)`` rows by ``q`` columns, so ``remap`` writes the
  contract's ``(m̂, m̂, Ny, Nx, C)`` array directly, without a transpose.
* **Devignetting.** The white image is demosaiced and resampled the same way, and the decoded value
  is ``remap(capture) / remap(white)``: the ratio of two linearly resampled images, which is the scene
  radiance in units of the white image, white balance included for colour sensors. Samples where the
  white image is darker than ``dark_fraction`` of its bright level (outside the main lens aperture,
  between micro images) carry no signal and are set to 0, never NaN.
* **Demosaicing** (Bayer captures) before resampling, by OpenCV: ``"fast"`` is bilinear
  interpolation (linear, so the ratio above stays an exact weighted average of radiance);
  ``"careful"`` is OpenCV's edge-aware (EA) variant, sharper on edges inside a micro image.
* **Interpolation** of the resampling: ``"nearest"``, ``"linear"``, ``"cubic"``, ``"lanczos"`` (OpenCV's
  4-lobed Lanczos): a speed/accuracy trade measured in ``docs/benchmarks.md``.
* **Hexagonal grids** are decoded at their own lens centres, then each view is resampled onto a
  rectangular lens grid of the same pitch (:func:`hex_to_rect`): lens rows 1 pitch apart, columns
  centred half-way between the lenses of even rows, linear interpolation along and across rows.

Non-finite pixels (NaN, inf) in a float capture or white image are refused with an `LfprocError`
(one pass over the sensor, ~1 % of a decode): a decoded light field never carries them.

Crosstalk. The effective pixel of the outermost ring of views (k = 0 or m̂ − 1) reaches the edge of
its micro image, so any interpolation there also reads the neighbouring micro image: those views are
contaminated where micro images touch (a main lens faster than the micro lenses). Against the
simulator's ideal views (9 µm pixels, 250 µm lenses, m̂ = 25) the inner views decode at 46 dB PSNR
with linear interpolation and the outer ring at 25 dB; with the usual f-number-matched main lens the
outer ring lies outside the aperture anyway (:func:`lfproc.geometry.views_inside_aperture`).

The white image's views depend only on the white image, the grid and the settings, so a
:class:`Decoder` computes them once and then decodes any number of captures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import LfprocError
from .grid import LensGrid

INTERPOLATIONS = ("nearest", "linear", "cubic", "lanczos")
DEMOSAIC_METHODS = ("fast", "careful")
#: OpenCV's Bayer codes are named after the second row's pixels: our top-left 2x2 -> their name
_CV_BAYER = {"RGGB": "BayerBG", "BGGR": "BayerRG", "GRBG": "BayerGB", "GBRG": "BayerGR"}
_CV_MAX_SIZE = 32000  # cv2.remap requires every image side below SHRT_MAX


def _cv2():
    import cv2
    return cv2


def sample_positions(grid: LensGrid, m_hat: int) -> tuple[np.ndarray, np.ndarray]:
    """Sensor positions (x, y) of every view sample, each shaped ``(m̂, m̂, rows, cols)``, float64.

    View k is read (k − c)·pitch/m̂ sensor pixels from the lens centre along the lattice axes
    (contract: view index and lens index increase with the sensor coordinate).
    """
    if m_hat < 1 or m_hat % 2 == 0:
        raise LfprocError(f"micro image size must be odd and >= 1, got {m_hat}")
    c = (m_hat - 1) // 2
    step = grid.pitch_px / m_hat
    u, v = grid.axes
    centers = grid.centers_xy_px()                              # (rows, cols, 2)
    k = (np.arange(m_hat) - c) * step                           # offsets along an axis
    off_x = k[None, :] * u[0] + k[:, None] * v[0]               # (ky, kx)
    off_y = k[None, :] * u[1] + k[:, None] * v[1]
    x = centers[None, None, :, :, 0] + off_x[:, :, None, None]
    y = centers[None, None, :, :, 1] + off_y[:, :, None, None]
    return x, y


def demosaic(mosaic: np.ndarray, cfa: str, method: str = "fast") -> np.ndarray:
    """Demosaic a linear Bayer mosaic ``(H, W)`` to ``(H, W, 3)`` RGB float32 with OpenCV.

    The data are shifted and scaled into 16 bits for OpenCV (its demosaicing works on integers) and
    back, so linear values keep 1/65535 of their range as precision; negative values (noise below the
    black level) are kept, not clipped.
    """
    if cfa not in _CV_BAYER:
        raise LfprocError(f"unknown Bayer pattern {cfa!r}; use one of {', '.join(_CV_BAYER)}")
    if method not in DEMOSAIC_METHODS:
        raise LfprocError(f"unknown demosaic method {method!r}; use one of {', '.join(DEMOSAIC_METHODS)}")
    cv2 = _cv2()
    data = np.asarray(mosaic, dtype=np.float32)
    if not np.all(np.isfinite(data)):   # the 16-bit conversion below would turn them into silent zeros
        raise LfprocError("the Bayer mosaic contains NaN or infinite pixels; replace them "
                          "(e.g. numpy.nan_to_num) before decoding")
    # offset by the minimum so negative (noise below black) values survive: bilinear weights sum to 1,
    # so adding the offset back afterwards is exact
    low = min(float(data.min()), 0.0) if data.size else 0.0
    top = float(data.max()) - low if data.size else 0.0
    scale = 65535.0 / top if top > 0 else 1.0
    as_u16 = np.clip((data - low) * scale + 0.5, 0, 65535).astype(np.uint16)
    code = getattr(cv2, f"COLOR_{_CV_BAYER[cfa]}2RGB" + ("_EA" if method == "careful" else ""))
    rgb = cv2.cvtColor(as_u16, code).astype(np.float32)
    rgb *= np.float32(1.0 / scale)
    rgb += np.float32(low)
    return rgb


def to_channels(image: np.ndarray, cfa: str, method: str) -> np.ndarray:
    """A sensor image as ``(H, W, C)`` float32: demosaiced if it is a Bayer mosaic."""
    data = np.asarray(image)
    if data.ndim == 2:
        if cfa != "none":
            return demosaic(data, cfa, method)
        return data.astype(np.float32, copy=False)[:, :, None]
    if data.ndim == 3:
        return data.astype(np.float32, copy=False)
    raise LfprocError(f"a sensor image must be 2-D or (H, W, C), got shape {data.shape}")


def remap_maps(grid: LensGrid, m_hat: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The float32 ``cv2.remap`` maps of every view row ky, each ``(m̂·rows, cols)`` (see :func:`sample_positions`)."""
    x, y = sample_positions(grid, m_hat)
    shape = (m_hat * grid.rows, grid.cols)
    return [(x[ky].reshape(shape).astype(np.float32), y[ky].reshape(shape).astype(np.float32))
            for ky in range(m_hat)]


def resample_views(image: np.ndarray, grid: LensGrid, m_hat: int, interpolation: str = "linear",
                   maps: list | None = None) -> np.ndarray:
    """Read an ``(H, W, C)`` image at the sample positions: ``(m̂, m̂, rows, cols, C)`` float32.

    Positions outside the image read 0. One ``cv2.remap`` per view row and block of lens rows
    (OpenCV limits every image side, maps included, to 32767 pixels).
    """
    if interpolation not in INTERPOLATIONS:
        raise LfprocError(f"unknown interpolation {interpolation!r}; use one of {', '.join(INTERPOLATIONS)}")
    cv2 = _cv2()
    flag = {"nearest": cv2.INTER_NEAREST, "linear": cv2.INTER_LINEAR, "cubic": cv2.INTER_CUBIC,
            "lanczos": cv2.INTER_LANCZOS4}[interpolation]
    h, w, channels = image.shape
    if max(h, w, grid.cols) >= _CV_MAX_SIZE:
        raise LfprocError(f"sensor image {w}x{h} ({grid.cols} lens columns) is beyond OpenCV's remap limit of "
                          f"{_CV_MAX_SIZE} px")
    maps = maps if maps is not None else remap_maps(grid, m_hat)
    out = np.empty((m_hat, m_hat, grid.rows, grid.cols, channels), dtype=np.float32)
    src = np.ascontiguousarray(image, dtype=np.float32)
    flat = out.reshape(m_hat, m_hat * grid.rows, grid.cols, channels)  # a view: rows (kx, r) of view row ky
    block = _CV_MAX_SIZE - 1
    for ky, (map_x, map_y) in enumerate(maps):
        for r0 in range(0, map_x.shape[0], block):
            r1 = min(r0 + block, map_x.shape[0])
            for ch0 in range(0, channels, 4):  # remap handles up to 4 channels at once
                ch1 = min(ch0 + 4, channels)
                plane = np.ascontiguousarray(src[:, :, ch0:ch1] if channels > 1 else src[:, :, 0])
                res = cv2.remap(plane, map_x[r0:r1], map_y[r0:r1], flag, borderMode=cv2.BORDER_CONSTANT,
                                borderValue=0)
                flat[ky, r0:r1, :, ch0:ch1] = res.reshape(r1 - r0, grid.cols, ch1 - ch0)
    return out


def hex_to_rect(views: np.ndarray, grid: LensGrid) -> tuple[np.ndarray, LensGrid]:
    """Resample views decoded on a hexagonal lens lattice onto a rectangular one of the same pitch.

    Hexagonal lens (r, q) sits at ((q + (r mod 2)/2)·p, r·(√3/2)·p) along (u, v). The rectangular
    lens (R, Q) is taken at ((Q + ½)·p, R·p): half-way between the lenses of even rows and exactly
    on the lenses of odd rows, so no column needs extrapolation. Each view is interpolated linearly
    along the two enclosing hexagonal rows and then linearly between them.

    Returns
    -------
    views : ndarray ``(m̂, m̂, R, cols − 1, C)``
    grid : LensGrid
        The rectangular grid of the resampled lens positions on the sensor.
    """
    if grid.kind != "hexagonal":
        return views, grid
    rows, cols = views.shape[2], views.shape[3]
    if rows < 2 or cols < 2:
        raise LfprocError("a hexagonal light field needs at least 2 lens rows and columns to resample")
    ratio = 1.0 / (math.sqrt(3.0) / 2.0)                 # hexagonal rows per rectangular row
    n_rect_rows = int(math.floor((rows - 1) / ratio + 1e-9)) + 1
    # Row by row into the one output array, through two small reused scratch rows: on large light
    # fields the cost is dominated by first touches of freshly allocated memory, not by arithmetic.
    out = np.empty(views.shape[:2] + (n_rect_rows, cols - 1, views.shape[4]), dtype=np.float32)
    upper = np.empty(views.shape[:2] + (cols - 1, views.shape[4]), dtype=np.float32)
    lower = np.empty_like(upper)

    def row_on_columns(r, dst):
        """Hexagonal row r read at the rectangular columns (Q + ½)·p."""
        if r % 2 == 0:   # lenses at q·p: half-way between lenses Q and Q + 1
            np.add(views[:, :, r, :-1], views[:, :, r, 1:], out=dst)
            dst *= np.float32(0.5)
        else:            # lenses at (q + ½)·p: exactly on lens Q
            dst[...] = views[:, :, r, :-1]

    for big_r in range(n_rect_rows):
        rho = big_r * ratio  # rectangular row R sits at hexagonal row coordinate R·2/√3
        r0 = min(int(math.floor(rho + 1e-9)), rows - 2)
        t = np.float32(rho - r0)
        row_on_columns(r0, upper)
        row_on_columns(r0 + 1, lower)
        np.multiply(upper, 1 - t, out=out[:, :, big_r])
        lower *= t
        out[:, :, big_r] += lower
    u, v = grid.axes
    origin = np.asarray(grid.origin_xy_px) + 0.5 * grid.pitch_px * u
    rect = LensGrid("rectangular", grid.pitch_px, grid.rotation_deg, tuple(origin), n_rect_rows, cols - 1,
                    grid.residual_rms_px)
    return out, rect


@dataclass(frozen=True, eq=False)
class Decoder:
    """Decodes captures that share one white image and grid (see the module docstring).

    Build it with :func:`make_decoder`; call it on a sensor image to get the views.
    """

    grid: LensGrid
    m_hat: int
    cfa: str
    interpolation: str
    demosaic_method: str
    sensor_shape: tuple          # (H, W) of the white image, which every capture must share
    channels: int
    maps: list                   # float32 remap maps per view row, computed once
    inverse_white: np.ndarray    # (m̂, m̂, rows, cols, C): 1 / white views where they carry signal, else 0
    output_grid: LensGrid        # lens positions of the decoded light field (rectangular, also for hex input)

    def __call__(self, sensor: np.ndarray, cfa: str | None = None) -> np.ndarray:
        """Views ``(m̂, m̂, Ny, Nx, C)`` float32 of one sensor image.

        ``cfa`` is the capture's colour filter when known: it must be the white image's.
        """
        sensor = np.asarray(sensor)
        if sensor.shape[:2] != self.sensor_shape:
            raise LfprocError(f"capture is {sensor.shape[1]}x{sensor.shape[0]} px but the white image is "
                              f"{self.sensor_shape[1]}x{self.sensor_shape[0]}; use the white image of the same camera")
        if cfa is not None and cfa != self.cfa and sensor.ndim == 2:
            raise LfprocError(f"capture has colour filter {cfa} but the white image has {self.cfa}; "
                              f"use a white image of the same camera and mode")
        if np.issubdtype(sensor.dtype, np.floating) and not np.all(np.isfinite(sensor)):
            raise LfprocError("the capture contains NaN or infinite pixels; replace them (e.g. numpy.nan_to_num) "
                              "before decoding")
        image = to_channels(sensor, self.cfa, self.demosaic_method)
        if image.shape[-1] != self.channels:
            raise LfprocError(f"capture has {image.shape[-1]} channels but the white image has {self.channels}; "
                              f"use a white image taken with the same camera settings")
        views = resample_views(image, self.grid, self.m_hat, self.interpolation, self.maps)
        views *= self.inverse_white
        if self.grid.kind == "hexagonal":
            views, _ = hex_to_rect(views, self.grid)
        return views


def make_decoder(white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str = "none", *,
                 interpolation: str = "linear", demosaic_method: str = "fast",
                 dark_fraction: float = 0.05) -> Decoder:
    """Prepare a :class:`Decoder`: remap maps and the white image's inverse views, computed once.

    Parameters
    ----------
    white : ndarray
        White image (linear), ``(H, W)`` mosaic/mono or ``(H, W, C)``.
    grid : LensGrid
        Fitted lattice (``lfproc.calibrate.estimate_grid``).
    m_hat : int
        Odd micro image size after resampling (``camera.m_hat``).
    cfa : str
        Bayer pattern of 2-D mosaics, or ``"none"``.
    dark_fraction : float
        Samples whose white value is below this fraction of the white's bright level (its 99th
        percentile) carry no signal and decode to 0.
    """
    if not 0 <= dark_fraction < 1:
        raise LfprocError(f"dark_fraction must be in [0, 1), got {dark_fraction}")
    if not np.all(np.isfinite(white)):  # before demosaicing, which would report the mosaic instead
        raise LfprocError("the white image contains NaN or infinite pixels; use a clean white image")
    white_img = to_channels(white, cfa, demosaic_method)
    maps = remap_maps(grid, m_hat)
    white_views = resample_views(white_img, grid, m_hat, interpolation, maps)
    bright = float(np.percentile(white_views, 99)) if white_views.size else 0.0
    if not bright > 0:
        raise LfprocError("the white image is black at every lens centre; check the white image and the grid")
    signal = white_views > dark_fraction * bright
    inverse = white_views  # in place: the white views themselves are not needed afterwards
    np.divide(1.0, white_views, out=inverse, where=signal)
    inverse[~signal] = 0.0
    output_grid = hex_to_rect(inverse[:1, :1], grid)[1] if grid.kind == "hexagonal" else grid
    return Decoder(grid, int(m_hat), cfa, interpolation, demosaic_method, tuple(np.shape(white)[:2]),
                   int(white_img.shape[-1]), maps, inverse, output_grid)


def decode(sensor: np.ndarray, white: np.ndarray, grid: LensGrid, m_hat: int, cfa: str = "none", **options):
    """Decode one sensor image into views ``(m̂, m̂, Ny, Nx, C)``; see :func:`make_decoder` for options."""
    return make_decoder(white, grid, m_hat, cfa, **options)(sensor)


def decode_capture(capture, white, grid: LensGrid, camera, **options):
    """Decode a :class:`lfproc.io.Capture` with its white image into a :class:`~lfproc.LightField`."""
    from .lightfield import LightField

    decoder = make_decoder(white.data, grid, camera.m_hat, white.cfa, **options)
    try:
        views = decoder(capture.data, capture.cfa)
    except LfprocError as exc:
        raise LfprocError(f"{capture.source}: {exc}") from None
    return LightField.from_views(views, camera, decoder.output_grid)
