"""Labels and legends never clip or overlap (issue 32): measured on the widest texts the code can produce.

The mosaic label was clipped at the right edge ("1.14 m|m"), the microscope's depth legend printed
"-12.72 µm-6.36 µm". Each check renders the picture and looks at its pixels: no text pixel in the right
margin, lines apart, every legend label inside the picture and apart from the others.
"""

from __future__ import annotations

import numpy as np
import pytest

from lfproc.outputs import add_label, metres, slice_label
from lfproc.outputs._display import label_layout

#: the widest labels lfproc writes under a preview (their longest numbers)
WIDEST = [
    slice_label(123456789.0, 98765432.1, float("inf")),
    f"z {-12345.6:+.1f} um | DOF {-12345.6:+.1f} to {-12000.1:+.1f} um",
    "225 of 15x15 views (black: no light or outside the aperture) | baseline 0.123 mm",
    "189 of 15x15 views (black: no light or outside the aperture) | 0.417 um per lens",
    "view [14, 14] | 123.45 mm from the centre",
    "view [14, 14] | 57.1 deg in the object",
]


def _text_pixels(picture: np.ndarray, height: int) -> np.ndarray:
    band = picture[height:]
    return (band if band.ndim == 2 else band.max(axis=2)) > 40


@pytest.mark.parametrize("width", [1024, 525, 300, 160, 96])
@pytest.mark.parametrize("text", WIDEST)
def test_preview_labels_stay_inside_the_picture(text, width):
    image = np.full((40, width, 3), 90, np.uint8)
    picture = add_label(image, text)
    size, lines, band, margin = label_layout(width, text)
    assert picture.shape == (40 + band, width, 3)
    ink = _text_pixels(picture, 40)
    columns = np.flatnonzero(ink.any(axis=0))
    rows = np.flatnonzero(ink.any(axis=1))
    assert columns.size and rows.size
    assert columns[0] >= 1 and columns[-1] <= width - 2            # nothing touches or leaves the edges
    assert rows[-1] <= band - 2                                      # the last line inside the band
    # every character drawn: the lines hold the whole text (wrapping only drops separators and spaces)
    assert "".join(lines).replace(" ", "").replace("|", "") == text.replace(" ", "").replace("|", "")
    # lines do not overlap: the rows of ink fall into as many separate runs as there are lines (or more)
    runs = 1 + int(np.count_nonzero(np.diff(rows) > 1))
    assert runs >= len(lines)


def test_a_long_label_on_a_wide_picture_is_one_line_and_on_a_narrow_one_wraps():
    text = WIDEST[2]
    assert len(label_layout(1400, text)[1]) == 1
    assert len(label_layout(160, text)[1]) > 1


def test_grey_previews_keep_one_channel_with_their_label():
    picture = add_label(np.full((30, 200), 120, np.uint8), "focus 1.14 m | DOF 1.02 m to 1.31 m")
    assert picture.ndim == 2 and picture[:30].max() == 120 and picture[30:].max() > 200


def test_metres_are_short():
    assert metres(float("inf")) == "inf" and metres(123456789.0) == "123457 m"


@pytest.mark.parametrize("microscope", [False, True])
def test_depth_legend_labels_are_inside_and_apart(microscope):
    """The depth preview's legend with its widest labels: every label drawn inside the picture, none on
    another (text rows of the legend column fall into separate runs, one per drawn label)."""
    from lfproc.depth._preview import preview_image

    rng = np.random.default_rng(3)
    if microscope:
        values = rng.uniform(-12345.6, 12000.0, (28, 28))           # "-1.235e+04 um": the widest z labels
        picture = preview_image(None, z_um=values)
    else:
        values = rng.uniform(101.0, 98765432.0, (53, 75))
        values[0, 0] = np.inf
        picture = preview_image(values)
    body_w = 480 if not microscope else 28 * round(480 / 28)
    legend = picture[:, body_w + 10 + 18:]                           # right of the colour bar
    ink = legend.min(axis=2) < 128
    assert not ink[:, -3:].any() and not ink[-3:, :].any()            # nothing reaches the right or bottom edge
    rows = np.flatnonzero(ink[:, 4:].any(axis=1))                    # the tick labels (after the tick marks)
    runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1)
    assert len(runs) >= 3 and all(len(run) <= 14 for run in runs)    # separate lines, none two labels tall


# ------------------------------------------------------------------ numbers read the right way
def _camera(name):
    from lfproc import Camera
    from conftest import SAMPLES

    return Camera.from_toml(SAMPLES / "cameras" / f"{name}.toml")


def test_ranges_read_near_to_far_and_low_to_high():
    """Issue 32: "in focus from 1.71 um to -1.71 um", "DOF -65.0 - -36.3 um": a microscope's DOF is written
    from low to high z, a camera's from near to far, joined by "to" (never a minus sign between numbers)."""
    import io
    import re

    from lfproc.cli.common import describe_slices
    from lfproc.outputs import slice_labels

    scope = _camera("lfm-20x")
    for label in slice_labels(scope, [-3.0, 0.0, 2.0]):
        low, high = (float(v) for v in re.search(r"DOF ([+-][\d.]+) to ([+-][\d.]+) um", label).groups())
        assert low < high
    out = io.StringIO()
    describe_slices(scope, [-3.0, 0.0, 2.0], out=out)
    pairs = re.findall(r"in focus \[([+-][\d.]+), ([+-][\d.]+)\] µm", out.getvalue())
    assert len(pairs) == 3 and all(float(lo) < float(hi) for lo, hi in pairs)
    camera = _camera("paper-f100-b10")
    for label in slice_labels(camera, [0.0, 0.5, 2.0]):
        near, far = re.search(r"DOF ([\d.]+|inf) m? ?to ([\d.]+ m|inf)", label).groups()
        assert float(near.split()[0]) < (float("inf") if far == "inf" else float(far.split()[0]))


def test_microscopes_report_an_equivalent_na_and_cameras_an_f_number():
    """Issue 32: "f/21 equivalent" for a microscope; microscopists think in NA. The NA of all views is the
    objective's (views outside it carry no light); fewer views, a smaller NA, M / (2 N_eq)."""
    from lfproc import geometry

    scope = _camera("lfm-20x")
    assert geometry.aperture_text(scope).startswith("NA ") and "f/" not in geometry.aperture_text(scope)
    assert geometry.equivalent_numerical_aperture(scope) == pytest.approx(0.5)
    narrow = geometry.equivalent_numerical_aperture(scope, 1.0)
    assert narrow == pytest.approx(20.0 / (2 * geometry.equivalent_f_number(scope, 1.0)), rel=1e-12)
    assert narrow < 0.5
    camera = _camera("paper-f100")
    assert geometry.aperture_text(camera).startswith("f/")
