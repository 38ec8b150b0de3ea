"""Depth at the edges of the scene (issue 20): planes from a = 0.25 to 2.5 side by side, reaching the image
border, and a near card in front of one of them. Every textured plane gets a finite depth on at least 80 % of
its interior lenses (image-border lenses included) with a median error of at most 5 % of its DOF; the lenses of
a far plane right next to the near card get their own depth from the views that see them."""

import numpy as np
import pytest
from scipy import ndimage

import lfproc
from lfproc import Camera, geometry, simulate
from lfproc.decode import make_decoder
from lfproc.lightfield import LightField
from lfproc.simulate import Noise, Plane, Scene
from lfproc.camera import MainLens

PLANE_A = (0.25, 0.8, 1.5, 2.5)
CARD_A = 2.2
SHAPE = (330, 460)
LENSES_PER_FEATURE = 2.5


def camera(cfa):
    return Camera(0.009, 0.1, 0.4, MainLens(50.0, 50.0, f_number=4.0), black_level=64, white_level=16383, cfa=cfa, name="edges")


def scene_for(cam):
    """Four strips, each a quarter of the frame wide and taller than it, at the four a; a near card over the
    second strip. Textures have features of about 2.5 lenses in the image."""
    h, w = SHAPE
    planes = []
    for i, dist in enumerate(geometry.slice_distance_mm(cam, PLANE_A)):
        mag = (dist - cam.main_optics.focal_length_mm) / cam.main_optics.focal_length_mm      # object mm per sensor mm
        half_w, half_h = w / 2 * cam.pixel_pitch_mm * mag * 1.02, h / 2 * cam.pixel_pitch_mm * mag * 1.2
        x0 = -half_w + i * half_w / 2
        planes.append(Plane(float(dist), Noise(feature_mm=LENSES_PER_FEATURE * cam.mla_pitch_mm * mag, seed=3 + i,
                                               low=0.1, high=0.9), region_mm=(x0, x0 + half_w / 2, -half_h, half_h)))
    dist = float(geometry.slice_distance_mm(cam, CARD_A))
    mag = (dist - cam.main_optics.focal_length_mm) / cam.main_optics.focal_length_mm
    cx, size = (-w / 2 + 1.5 * w / 4) * cam.pixel_pitch_mm * mag, w / 16 * cam.pixel_pitch_mm * mag
    planes.append(Plane(dist, Noise(feature_mm=LENSES_PER_FEATURE * cam.mla_pitch_mm * mag, seed=12, low=0.1,
                                    high=0.9), region_mm=(cx - size, cx + size, -2 * size, 2 * size)))
    return Scene(tuple(planes), background=0.05)


@pytest.fixture(scope="module", params=["none", "RGGB"])
def rendered(request):
    cam = camera(request.param)
    sim = simulate.render(cam, scene_for(cam), SHAPE, rotation_deg=0.2, offset_px=(0.3, 0.1),
                          shot_noise_photons=200000, seed=3, ideal_views=False)
    levels = lambda dn: (dn.astype(np.float32) - cam.black_level) / (cam.white_level - cam.black_level)
    decoder = make_decoder(levels(sim.white), sim.grid, cam.m_hat, cam.cfa)
    views = decoder(levels(sim.raw), cam.cfa)
    lf = LightField.from_views(views, cam, decoder.output_grid, decoder.views_delivered)
    return dict(camera=cam, sim=sim, depth=lfproc.depth_map(lf))


def scores(rendered, index, region):
    cam, depth = rendered["camera"], rendered["depth"]
    a = (*PLANE_A, CARD_A)[index]
    dof = float(geometry.slice_geometry(cam, a).dof_mm)
    estimate = depth.distance_mm[region]
    known = np.isfinite(estimate)
    error = np.abs(estimate[known] - rendered["sim"].depth_mm[region][known]) / dof
    return known.mean(), (float(np.median(error)) if known.any() else np.inf)


@pytest.mark.parametrize("index", range(len(PLANE_A)))
def test_every_plane_has_depth_up_to_the_image_border(rendered, index):
    # on the Bayer render the nearest plane (a = 2.5) was known on 80 % of its lenses with a median error of
    # 9 % of its DOF while it matched on Rec. 709 luma over 3 x 3 lenses; the channel mean and a 5 x 5 box
    # brought it to 90 % and 3.6 % under bilinear demosaicing, rim-aware decoding (the default since) to
    # 100 % and 1.7 % (docs/depth.md, "Depth at the edges of the scene")
    label = rendered["sim"].plane_label
    interior = ndimage.binary_erosion(label == index, iterations=1, border_value=1)   # image border kept
    border = interior & ~np.pad(np.ones((label.shape[0] - 6, label.shape[1] - 6), bool), 3)
    assert interior.sum() > 100 and border.sum() > 30
    known, median = scores(rendered, index, interior)
    assert known >= 0.8 and median <= 0.05, (PLANE_A[index], known, median)
    known_border, median_border = scores(rendered, index, border)
    assert known_border >= 0.5 and median_border <= 0.08, (PLANE_A[index], known_border, median_border)


def test_a_far_plane_next_to_a_near_card_keeps_its_depth(rendered):
    label = rendered["sim"].plane_label
    card = label == len(PLANE_A)
    ring = ndimage.binary_dilation(card, iterations=3) & ~ndimage.binary_dilation(card, iterations=1) & (label == 1)
    assert ring.sum() > 20
    known, median = scores(rendered, 1, ring)
    # lenses 2-3 lenses from the card's edge: before the half apertures, a third of them got a depth, off by
    # 9-16 % of the DOF; the bound here is the plane interior's 5 % doubled (the card's edge blurs into them)
    assert known >= 0.7 and median <= 0.10, (known, median)


def test_matching_signal_weighs_a_pixels_own_sample_alike_at_every_bayer_site():
    """The mechanism behind the Bayer scatter: bilinear demosaicing (the textbook kernels, written out here)
    fills a pixel's missing colours from its neighbours in the micro image, i.e. from neighbouring views. The
    matching signal must give the pixel's own sample the same share at every site of the 2 x 2 pattern, so
    that every view's sample is the same blend of neighbouring views wherever the Bayer phase falls under a
    lens (Rec. 709 luma gives it 0.21 at a red site and 0.72 at a green one)."""
    from lfproc.depth._cost import luminance

    full = np.array([[1, 2, 1], [2, 4, 2], [1, 2, 1]], float) / 4      # red and blue: 1 site in 4
    cross = np.array([[0, 1, 0], [1, 4, 1], [0, 1, 0]], float) / 4     # green: 2 sites in 4
    rows, cols = np.mgrid[0:8, 0:8]
    site = {"R": (rows % 2 == 0) & (cols % 2 == 0), "G": (rows + cols) % 2 == 1, "B": (rows % 2 == 1) & (cols % 2 == 1)}
    shares = []
    for y, x in ((4, 4), (4, 5), (5, 4), (5, 5)):                       # R, G, G, B sites of RGGB
        impulse = np.zeros((8, 8))
        impulse[y, x] = 1.0                                            # a grey scene: one bright pixel
        rgb = np.stack([ndimage.convolve(impulse * site[ch], kernel, mode="constant")
                        for ch, kernel in (("R", full), ("G", cross), ("B", full))], axis=-1)
        signal = luminance(rgb.astype(np.float32))
        shares.append(float(signal[y, x]))
    assert np.ptp(shares) < 1e-6, shares
