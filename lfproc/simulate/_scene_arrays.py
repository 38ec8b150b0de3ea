"""The scene flattened into arrays for the numba kernels."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Camera
from ..errors import LfprocError
from ._scene import Scene
from ._textures import KIND_CHECKER, KIND_NOISE, KIND_SINUSOID, ImageTexture


@dataclass(frozen=True, eq=False)
class SceneArrays:
    """The scene flattened for the kernels, planes sorted nearest first (``order`` maps back to scene indices).

    ``params`` per plane: [low, high, p2, p3, p4, p5, p6] with
    checkerboard p2 = half period; sinusoid p2 = 2π/period, p3 = cos θ, p4 = sin θ, p5 = phase;
    noise p2 = 1/feature, p3 = seed; image p2 = width, p3 = height, p4 = offset into ``images``,
    p5 = rows, p6 = cols.

    ``frame`` per plane: the plane's axes e1, e2 and normal n (``Plane.frame()``, in plane coordinates
    x, y and depth) flattened, then 1.0 for a tilted plane (0.0: the kernels take the fronto-parallel
    path, z fixed).
    """

    z_mm: np.ndarray        # (P,) distance from H1U (of the centre point on the axis for a tilted plane)
    frame: np.ndarray       # (P, 10) e1, e2, n, tilted flag
    region: np.ndarray      # (P, 4) x0, x1, y0, y1 (±inf when unbounded)
    kind: np.ndarray        # (P,) int64
    params: np.ndarray      # (P, 7)
    center: np.ndarray      # (P, 2)
    tint: np.ndarray        # (P, 3)
    images: np.ndarray      # flat float32 RGB of all image textures
    background: np.ndarray  # (3,)
    order: np.ndarray       # (P,) scene index of each sorted plane

    @classmethod
    def uniform(cls, value: float) -> SceneArrays:
        """No planes, radiance ``value`` everywhere (the white image)."""
        return cls(np.zeros(0), np.zeros((0, 10)), np.zeros((0, 4)), np.zeros(0, np.int64), np.zeros((0, 7)),
                   np.zeros((0, 2)), np.zeros((0, 3)), np.zeros(1, np.float32), np.full(3, float(value)),
                   np.zeros(0, np.int64))

    @classmethod
    def build(cls, scene: Scene, camera: Camera) -> SceneArrays:
        inside = camera.main_optics.sensor_path_mm(camera.mla_path_mm)
        order = np.argsort([p.distance_mm for p in scene.planes], kind="stable").astype(np.int64)
        n = len(order)
        z = np.zeros(n)
        frame = np.zeros((n, 10))
        region = np.tile(np.array([-np.inf, np.inf, -np.inf, np.inf]), (n, 1))
        kind = np.zeros(n, np.int64)
        params = np.zeros((n, 7))
        center = np.zeros((n, 2))
        tint = np.ones((n, 3))
        images, image_size = [], 0
        for row, index in enumerate(order):
            plane = scene.planes[index]
            if plane.distance_mm <= inside:
                raise LfprocError(f"plane {plane.name or index} at {plane.distance_mm} mm is not in front of the main "
                                  f"lens ({inside:.3f} mm from the sensor); move it farther away")
            z[row] = plane.distance_mm - inside
            frame[row, :9] = plane.frame().ravel()
            frame[row, 9] = 1.0 if plane.tilted else 0.0
            tex = plane.texture
            kind[row] = tex.kind
            params[row, :2] = tex.levels()
            center[row] = plane.center_mm
            tint[row] = plane.tint
            if plane.region_mm is not None:
                region[row] = plane.region_mm
            if tex.kind == KIND_CHECKER:
                params[row, 2] = tex.period_mm / 2.0
            elif tex.kind == KIND_SINUSOID:
                angle = math.radians(tex.angle_deg)
                params[row, 2:6] = (2.0 * math.pi / tex.period_mm, math.cos(angle), math.sin(angle),
                                    math.radians(tex.phase_deg))
            elif tex.kind == KIND_NOISE:
                params[row, 2:4] = (1.0 / tex.feature_mm, tex.seed)
            elif isinstance(tex, ImageTexture):
                h, w = tex.pixels.shape[:2]
                params[row, 2:7] = (tex.width_mm, tex.height_mm, image_size, h, w)
                images.append(tex.pixels.ravel())
                image_size += tex.pixels.size
                cx, cy = plane.center_mm
                extent = (cx - tex.width_mm / 2, cx + tex.width_mm / 2, cy - tex.height_mm / 2, cy + tex.height_mm / 2)
                region[row] = (max(region[row, 0], extent[0]), min(region[row, 1], extent[1]),
                               max(region[row, 2], extent[2]), min(region[row, 3], extent[3]))
        flat = np.concatenate(images).astype(np.float32) if images else np.zeros(1, np.float32)
        background = np.asarray(scene.background, dtype=np.float64)
        return cls(z, frame, region, kind, params, center, tint, flat, background, order)

    def kernel_args(self):
        return (self.z_mm, self.frame, self.region, self.kind, self.params, self.center, self.tint, self.images,
                self.background)
