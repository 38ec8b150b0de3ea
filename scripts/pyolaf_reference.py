"""pyolaf's side of scripts/compare_pyolaf.py and scripts/bench_deconvolution.py: run it with pyolaf's Python.

pyolaf 0.2.1 (Karashchuk; the Python port of oLaF, Stefanoiu et al. 2019) is never a dependency of lfproc:
install it in a venv of its own (``python3 -m venv /work/pyolaf-venv; /work/pyolaf-venv/bin/pip install
pyolaf==0.2.1``) and give that Python to the lfproc scripts (``--pyolaf-python``); they call this file with
it and exchange NumPy files. Only pyolaf's public functions are called; the Richardson–Lucy loop (not part of
pyolaf's package) is written here after its example, with the guard on the back-projected ones its example
needs (a plane diverged to 7.5e11 without it).

    python pyolaf_reference.py layout OPTICS.json OUT.npz         # where its lenses and voxels sit
    python pyolaf_reference.py filter-shift OPTICS.json OUT.npz    # where each loop's filter step moves a voxel
    python pyolaf_reference.py patterns OPTICS.json OUT.npz       # forward patterns H for the depths
    python pyolaf_reference.py project OPTICS.json VOLUMES.npz OUT.npz      # H·volume (pyolaf's layout)
    python pyolaf_reference.py deconvolve OPTICS.json IMAGE.npy OUTDIR      # operators + RL on a rectified image

OPTICS.json: {"M", "NA", "n", "wavelength_um", "ftl_um", "pitch_um", "fs_um", "spacing_px", "superres",
"depths_um": [...], "image_px": [H, W]} (plus "iterations", "lanczos_window", "filter", "loops" for deconvolve).
pyolaf's lenslet phase uses k = 2π·n/λ (the immersion index) where the lenslets sit in air: its ``fm`` is
given as n·f_s so that its lenslets have the physical focal length f_s. Timings (wall and CPU seconds) and
the peak memory of this process are returned with the results.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import tempfile
import time

import numpy as np


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _camera(optics: dict):
    import yaml
    from pyolaf.geometry import LFM_setCameraParams

    config = {"gridType": "reg", "focus": "single", "M": optics["M"], "NA": optics["NA"], "ftl": optics["ftl_um"],
              "lensPitch": optics["pitch_um"], "pixelPitch": optics["pitch_um"] / optics["spacing_px"],
              "fm": optics["fs_um"] * optics["n"], "mla2sensor": optics["fs_um"], "tube2mla": 0, "plenoptic": 1,
              "n": optics["n"], "WaveLength": optics["wavelength_um"], "uLensMask": 1}
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as fh:
        yaml.safe_dump(config, fh)
    try:
        return LFM_setCameraParams(fh.name, optics["spacing_px"])
    finally:
        os.remove(fh.name)


def _geometry(optics: dict):
    from pyolaf.geometry import LFM_computeGeometryParameters

    camera = _camera(optics)
    depths = [float(v) for v in optics["depths_um"]]
    step = depths[1] - depths[0] if len(depths) > 1 else 1.0
    centres, resolution, _, _ = LFM_computeGeometryParameters(
        camera, np.array([]), [min(depths), max(depths)], step, optics["superres"], False,
        imgSize=np.array(optics["image_px"]))
    resolution["depths"] = np.array(depths)
    return camera, centres, resolution


def _forward_patterns(camera, centres, resolution):
    """pyolaf's forward patterns H (its LFM_computeLFMatrixOperators without the backward ones)."""
    from pyolaf import lf

    depth_range = np.array([resolution["depths"].min(), resolution["depths"].max()]) + camera["offsetFobj"]
    size = lf.LFM_computePSFsize(depth_range[np.argmax(np.abs(depth_range))], camera)
    resolution["usedLensletCenters"] = lf.LFM_getUsedCenters(size, centres)
    half = int(max(resolution["Nnum"][1] * size, 2 * resolution["Nnum"][1]))
    for axis, name in ((0, "y"), (1, "x")):
        resolution[f"{name}space"] = resolution["sensorRes"][axis] * np.arange(-half, half + 1)
        resolution[f"{name}MLspace"] = resolution["sensorRes"][axis] * np.arange(-resolution["Nnum_half"][axis] + 1,
                                                                                 resolution["Nnum_half"][axis])
    psf = lf.LFM_calcPSFAllDepths(camera, resolution)
    mla = lf.LFM_mlaTransmittance(camera, resolution, lf.LFM_ulensTransmittance(camera, resolution))
    return lf.LFM_computeForwardPatternsWaves(psf, mla, camera, resolution), half


def _layout(centres, resolution, image_px, tex_px) -> dict:
    """Where pyolaf's projections put lens (a, b)'s centre pixel and centre voxel (0-based indices; its
    get_indices_forward/backward: pixel px + ⌈H/2⌉ − 1, voxel vox + ⌈h/2⌉)."""
    offset_img = np.ceil(np.array(image_px) / 2.0)
    offset_vol = np.ceil(np.array(tex_px) / 2.0)
    return {"lens_px": centres["px"] + offset_img - 1, "lens_vox": centres["vox"] + offset_vol}


def layout(optics: dict, out: str) -> None:
    """Only where pyolaf puts its lenses and voxels for this image size (no PSFs)."""
    _, centres, resolution = _geometry(optics)
    image_px = np.array(optics["image_px"])
    tex = np.ceil(image_px * resolution["texScaleFactor"]).astype(int)
    tex = tex + (1 - tex % 2)
    np.savez(out, tex_px=tex, **_layout(centres, resolution, image_px, tex))


#: the filter step of each loop of :func:`deconvolve`: the example's fftshift, or ifftshift (centred)
LOOP_SHIFTS = {"example": np.fft.fftshift, "centred": np.fft.ifftshift}


def filter_shift(optics: dict, out: str) -> None:
    """Where one filter step of each loop (``abs(SHIFT(ifft2(K·fft2(v))))`` with K from pyolaf's own
    ``lanczosfft``; SHIFT the example's fftshift or the centred loop's ifftshift) moves a single voxel of an
    odd-sized plane, with the identity kernel (width 1): ``shift_example``, ``shift_centred`` (y, x)."""
    from pyolaf.aliasing import lanczosfft

    size = 9
    kernel = lanczosfft(np.array([size, size, 1]), np.array([[1, 1]]), 4)[:, :, 0]
    plane = np.zeros((size, size))
    plane[size // 2, size // 2] = 1.0
    moved = {f"shift_{loop}": np.argwhere(np.abs(shift(np.fft.ifft2(kernel * np.fft.fft2(plane)))) > 0.5)[0]
             - size // 2 for loop, shift in LOOP_SHIFTS.items()}
    np.savez(out, **moved)


def patterns(optics: dict, out: str) -> None:
    from pyolaf import lf

    t0, c0 = time.time(), _cpu()
    camera, centres, resolution = _geometry(optics)
    h, half = _forward_patterns(camera, centres, resolution)
    raw = {f"raw_{i}_{j}_{c}": h[i, j, c].toarray() for i in range(h.shape[0]) for j in range(h.shape[1])
           for c in range(h.shape[2])}
    clamped = lf.ignoreSmallVals(h, 0.005)
    used = {f"H_{i}_{j}_{c}": clamped[i, j, c].toarray() for i in range(h.shape[0]) for j in range(h.shape[1])
            for c in range(h.shape[2])}
    np.savez(out, half=half, depths=resolution["depths"], wall=time.time() - t0, cpu=_cpu() - c0, **raw, **used)


def project(optics: dict, volumes: str, out: str) -> None:
    from pyolaf import lf
    from pyolaf.project import LFM_forwardProject

    camera, centres, resolution = _geometry(optics)
    h, _ = _forward_patterns(camera, centres, resolution)
    h = lf.ignoreSmallVals(h, 0.005)
    image_px = np.array(optics["image_px"])
    stored = np.load(volumes)
    results = {}
    for name in stored.files:
        volume = stored[name].astype(np.float32)
        results[name] = np.asarray(LFM_forwardProject(h, volume, centres, resolution, image_px, camera["range"],
                                                      step=8))
    tex_px = stored[stored.files[0]].shape[:2]
    np.savez(out, **results, **_layout(centres, resolution, image_px, tex_px))


def deconvolve(optics: dict, image: str, out: str) -> None:
    """pyolaf's operators, then Richardson–Lucy as its example runs it, on a rectified image (``spacing_px``
    pixels per lens, a lens centre at pyolaf's centre pixel), once per loop of ``optics["loops"]``:

    "example"
        the example's filter step as written, ``abs(fftshift(ifft2(K·fft2(v))))`` (oLaF's deconvEMS.m too):
        K is the FFT of a kernel centred at index ⌊n/2⌋ of the odd-sized plane, and fftshift moves by ⌊n/2⌋
        again, so each step moves the volume by n − 1 ≡ −1 voxel in y and x;
    "centred"
        the same step with ``ifftshift`` (a move by −⌊n/2⌋), which puts the kernel's centre back at the origin:
        the filter is then a convolution centred on each voxel, nothing else changes.

    Writes ``OUT/pyolaf_LOOP.npz`` per loop: the volume, the timings of the operators (shared) and of that
    loop, CPU of the operators + that loop, the peak memory of this process."""
    from pyolaf.aliasing import LFM_computeDepthAdaptiveWidth, lanczosfft
    from pyolaf.lf import LFM_computeLFMatrixOperators
    from pyolaf.project import LFM_backwardProject, LFM_forwardProject

    lf_image = np.load(image).astype(np.float32)
    optics = dict(optics, image_px=list(lf_image.shape))
    shape = np.array(lf_image.shape)
    t0, c0 = time.time(), _cpu()
    camera, centres, resolution = _geometry(optics)
    t_geometry = time.time() - t0
    h, ht = LFM_computeLFMatrixOperators(camera, resolution, centres)
    tex = np.ceil(np.array(lf_image.shape) * resolution["texScaleFactor"]).astype(int)
    tex = tex + (1 - tex % 2)
    volume_size = np.append(tex, len(resolution["depths"])).astype(int)
    kernel = lanczosfft(volume_size, LFM_computeDepthAdaptiveWidth(camera, resolution), optics.get("lanczos_window", 4))
    crange = camera["range"]
    ones = np.ones(volume_size, dtype=np.float32)
    ones_forward = LFM_forwardProject(h, ones, centres, resolution, shape, crange, step=8)
    ones_back = LFM_backwardProject(ht, ones_forward, centres, resolution, tex, crange, step=8)
    t_operators, c_operators = time.time() - t0, _cpu() - c0
    for loop in optics.get("loops", ["example"]):
        shift = LOOP_SHIFTS[loop]
        t_loop, c_loop = time.time(), _cpu()
        volume = ones.copy()
        per_iteration = []
        for i in range(int(optics.get("iterations", 8))):
            t1 = time.time()
            guess = ones_forward if i == 0 else LFM_forwardProject(h, volume, centres, resolution, shape, crange,
                                                                   step=10)
            with np.errstate(divide="ignore", invalid="ignore"):
                error = lf_image / guess * ones_forward
            error[~np.isfinite(error)] = 0
            back = LFM_backwardProject(ht, error, centres, resolution, tex, crange, step=10)
            with np.errstate(divide="ignore", invalid="ignore"):
                back = back / ones_back
            back[~np.isfinite(back)] = 0
            back[ones_back < 1e-3 * np.median(ones_back)] = 0      # the guard the ant leg needed
            volume = volume * back
            if optics.get("filter", True):
                for j in range(volume.shape[2]):
                    volume[:, :, j] = np.abs(shift(np.fft.ifft2(kernel[:, :, j] * np.fft.fft2(volume[:, :, j]))))
            volume[~np.isfinite(volume)] = 0
            per_iteration.append(time.time() - t1)
        np.savez(os.path.join(out, f"pyolaf_{loop}.npz"), volume=volume, depths=resolution["depths"], loop=loop,
                 geometry_s=t_geometry, operators_s=t_operators, operators_cpu_s=c_operators,
                 iteration_s=np.array(per_iteration), wall_s=t_operators + time.time() - t_loop,
                 cpu_s=c_operators + _cpu() - c_loop,
                 peak_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
                 **_layout(centres, resolution, lf_image.shape, tex))


if __name__ == "__main__":
    mode, config = sys.argv[1], json.loads(open(sys.argv[2]).read())
    {"layout": layout, "filter-shift": filter_shift, "patterns": patterns, "project": project, "deconvolve": deconvolve}[mode](config, *sys.argv[3:])
