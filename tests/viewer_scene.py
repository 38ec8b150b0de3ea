"""A small rendered capture for the viewer tests: a near textured card over a far textured wall."""

import json
from pathlib import Path

import numpy as np
from scipy import ndimage

from lfproc import Camera, geometry, simulate
from lfproc.io import write_image
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

NEAR_A, FAR_A = 1.3, 0.4


def camera():
    return Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), black_level=64, white_level=16383, name="viewer-test")


def render_capture(folder: Path, seed: int = 7, flip: bool = False) -> dict:
    """Write capture.png, white.png, camera.toml and the true grid.json into ``folder``; returns the truth.

    ``distances``: the two planes' distances (card, wall); ``label``: (rows, cols) plane index of each
    lens (-1 background); ``flip`` puts the card on the right instead of the left.
    """
    cam = camera()
    d_near, d_far = geometry.slice_distance_mm(cam, [NEAR_A, FAR_A])
    region = (0, 40, -40, 40) if flip else (-40, 0, -40, 40)
    scene = Scene((Plane(d_near, Noise(feature_mm=2.5, seed=seed + 1, low=0.1, high=0.9), region_mm=region),
                   Plane(d_far, Noise(feature_mm=6.0, seed=seed, low=0.1, high=0.9))), background=0.05)
    sim = simulate.render(cam, scene, (300, 420), rotation_deg=0.2, offset_px=(0.3, 0.1), pixel_samples=2,
                          aperture_samples=3, shot_noise_photons=200000, seed=seed, ideal_views=False)
    folder.mkdir(parents=True, exist_ok=True)
    write_image(folder / "capture.png", sim.raw)
    write_image(folder / "white.png", sim.white)
    (folder / "camera.toml").write_text(cam.to_toml())
    # the true lens grid, so that decoded lens (row, col) indices are those of ``label``
    grid = dict(sim.grid.to_json_dict(), white_image=str(folder / "white.png"))
    (folder / "grid.json").write_text(json.dumps(grid))
    return dict(camera=cam, distances=(float(d_near), float(d_far)), label=sim.plane_label, folder=folder)


def inner_lenses(label: np.ndarray, index: int, erode: int = 4) -> np.ndarray:
    """Lenses that see plane ``index``, away from its edges and the image border."""
    region = ndimage.binary_erosion(label == index, iterations=erode)
    region[:erode] = region[-erode:] = False
    region[:, :erode] = region[:, -erode:] = False
    return region
