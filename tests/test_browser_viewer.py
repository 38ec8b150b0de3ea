"""The viewer in a real browser (headless Chromium driven by Selenium): click a rendered plane and read
its distance, move the slider and the viewpoint, take a screenshot.

Chromium and chromedriver come from Debian's packages (``apt-get install chromium chromium-driver``;
``.ci/run`` installs them). Outside CI a machine without them skips these tests with that reason; in
CI (``CI=true``) a missing browser is a failure, so the tests always run there.
"""

import json
import os
import re
import shutil

import numpy as np
import pytest

from conftest import run_cli
from viewer_scene import inner_lenses, render_capture

BROWSER_ARGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--window-size=1280,1000")


def _browser_paths():
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    return chromium, driver


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    chromium, driver = _browser_paths()
    if not (chromium and driver):
        message = "Chromium or chromedriver missing: apt-get install -y chromium chromium-driver"
        if os.environ.get("CI") == "true":
            pytest.fail(message + " (CI must run the browser tests)")
        pytest.skip(message)  # outside CI only: a developer machine without a browser
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        if os.environ.get("CI") == "true":
            raise
        pytest.skip("selenium missing: pip install -e '.[test]'")  # outside CI only, as above

    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for arg in BROWSER_ARGS:
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})  # console, requests
    options.add_argument(f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}")  # new and empty
    driver_ = webdriver.Chrome(options=options, service=Service(driver))
    driver_.set_page_load_timeout(30)
    yield driver_
    driver_.quit()


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    folder = tmp_path_factory.mktemp("viewer-scene")
    truth = render_capture(folder)
    out = folder / "viewer"
    proc = run_cli("viewer", folder / "capture.png", "--camera", folder / "camera.toml", "--calib",
                   folder / "grid.json", "-o", out)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "geometry.json").read_text())
    return dict(truth, out=out, data=data)


_LEGEND_BOXES = """
var box = document.getElementById('legend-ticks').getBoundingClientRect();
return [[box.left, box.right]].concat(Array.prototype.map.call(document.querySelectorAll('#legend-ticks span'),
  function (s) { var r = s.getBoundingClientRect();
                 return [r.left, r.right, getComputedStyle(s).visibility !== 'hidden']; }));
"""


def assert_legend_labels_apart(browser):
    """Issue 32 ("-12.72 µm-6.36 µm"): with the widest tick labels the page can show, at several window
    widths, the visible legend labels stay inside the legend and apart from each other."""
    import time

    size = browser.get_window_size()
    try:
        _legend_at_widths(browser, time)
    finally:
        browser.set_window_size(size["width"], size["height"])
        browser.refresh()


def _legend_at_widths(browser, time):
    for width in (1400, 900, 600):
        browser.set_window_size(width, 1000)
        browser.execute_script("document.querySelectorAll('#legend-ticks span').forEach(function (s) {"
                               "s.textContent = '-12345.67 \u00b5m'; }); window.dispatchEvent(new Event('resize'));")
        time.sleep(0.2)
        (left, right), *spans = browser.execute_script(_LEGEND_BOXES)
        shown = sorted((a, b) for a, b, visible in spans if visible)
        assert len(shown) >= (2 if width >= 1400 else 1), (width, spans)
        assert all(left - 0.5 <= a and b <= right + 0.5 for a, b in shown), (width, left, right, shown)
        assert all(b0 + 1 <= a1 for (_, b0), (a1, _) in zip(shown, shown[1:])), (width, shown)


def _open(browser, page):
    from selenium.webdriver.support.ui import WebDriverWait

    browser.get((page["out"] / "index.html").as_uri())
    WebDriverWait(browser, 10).until(lambda d: d.execute_script("return document.body.dataset.ready === 'true'"))
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert errors == [], errors
    return browser.find_element("id", "photo")


def _click_lens(browser, photo, page, jy, jx):
    from selenium.webdriver.common.action_chains import ActionChains

    ny, nx = page["data"]["lens_shape"]
    size = photo.size
    dx = (jx + 0.5) / nx * size["width"] - size["width"] / 2  # Selenium 4: offsets from the element's centre
    dy = (jy + 0.5) / ny * size["height"] - size["height"] / 2
    ActionChains(browser).move_to_element_with_offset(photo, int(round(dx)), int(round(dy))).click().perform()


def _shown_distance_mm(browser):
    text = browser.find_element("id", "here-distance").text
    match = re.fullmatch(r"([0-9.]+) m", text)
    assert match, text
    return float(match.group(1)) * 1000.0


@pytest.mark.parametrize("plane", [0, 1], ids=["near card", "far wall"])
def test_click_on_a_plane_shows_its_distance_within_the_slice_dof(browser, page, plane):
    photo = _open(browser, page)
    lenses = np.argwhere(inner_lenses(page["label"], plane))
    jy, jx = lenses[len(lenses) // 2]
    _click_lens(browser, photo, page, jy, jx)
    k = int(browser.find_element("id", "readout").get_attribute("data-slice"))
    chosen = page["data"]["slices"][k]
    truth = page["distances"][plane]
    shown = _shown_distance_mm(browser)
    assert abs(shown - truth) <= chosen["dof_mm"], (shown, truth, chosen)
    assert photo.get_attribute("src").endswith(chosen["image"])
    assert browser.find_element("id", "slider").get_attribute("value") == str(k)
    # everything the page requested came from its own folder: no network access
    requests = [json.loads(entry["message"])["message"] for entry in browser.get_log("performance")]
    folder = page["out"].as_uri() + "/"
    loaded = {r["params"]["request"]["url"] for r in requests if r["method"] == "Network.requestWillBeSent"
              and r["params"].get("documentURL", "").startswith(folder)}
    assert len(loaded) > 3 and all(url.startswith(folder) for url in loaded), loaded


def test_slider_and_viewpoint_change_the_picture_and_a_screenshot_is_taken(browser, page, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    photo = _open(browser, page)
    slices = page["data"]["slices"]
    slider = browser.find_element("id", "slider")
    start = int(slider.get_attribute("value"))
    before_src, before_png = photo.get_attribute("src"), photo.screenshot_as_png
    slider.send_keys(Keys.ARROW_DOWN if start == len(slices) - 1 else Keys.ARROW_UP)   # any slider direction
    moved = int(slider.get_attribute("value"))
    assert moved != start and photo.get_attribute("src").endswith(slices[moved]["image"])
    assert photo.screenshot_as_png != before_png
    assert before_src != photo.get_attribute("src")

    after_slider = photo.screenshot_as_png
    width = photo.size["width"]
    ActionChains(browser).move_to_element(photo).click_and_hold().move_by_offset(width // 4, 0) \
        .move_by_offset(width // 8, 0).release().perform()
    shown = photo.get_attribute("data-shown")
    assert shown.startswith("view "), shown
    ky, kx = map(int, shown[5:].split(","))
    centre = page["data"]["views"]["center"]
    assert ky == centre and kx > centre  # dragging right moves the viewpoint to larger kx
    assert photo.screenshot_as_png != after_slider
    assert "mm from the central view" in browser.find_element("id", "view-readout").text

    before_key = photo.screenshot_as_png
    browser.find_element("tag name", "body").send_keys(Keys.ARROW_LEFT)
    assert photo.get_attribute("data-shown") == f"view {ky},{kx - 1}"
    assert photo.screenshot_as_png != before_key

    shot = tmp_path / "viewer.png"
    assert browser.save_screenshot(str(shot))
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_index_of_several_captures_opens_each_page_and_back(browser, page, tmp_path):
    from selenium.webdriver.support.ui import WebDriverWait

    folder = page["folder"]
    for stem in ("first", "second"):
        shutil.copy(folder / "capture.png", tmp_path / f"{stem}.png")
    out = tmp_path / "site"
    proc = run_cli("viewer", tmp_path / "first.png", tmp_path / "second.png", "--camera", folder / "camera.toml",
                   "--calib", folder / "grid.json", "--a", "0.4,1.3", "-o", out)
    assert proc.returncode == 0, proc.stderr
    browser.get((out / "index.html").as_uri())
    cards = browser.find_elements("css selector", "a.card")
    assert [c.find_element("css selector", ".name").text for c in cards] == ["first", "second"]
    cards[1].click()
    WebDriverWait(browser, 10).until(lambda d: d.execute_script("return document.body.dataset.ready === 'true'"))
    assert browser.find_element("id", "title").text == "lfproc viewer: second"
    WebDriverWait(browser, 10).until(  # its picture loads from the page's own folder
        lambda d: d.execute_script("return document.getElementById('photo').naturalWidth") > 0)
    browser.find_element("id", "back").click()
    WebDriverWait(browser, 10).until(lambda d: d.current_url == (out / "index.html").as_uri())


def test_aperture_control_and_viewpoint_marker(browser, page):
    """Issue 20: choosing a synthetic aperture shows its slices with their DOF in metres; an arrow key moves
    the perspective and the aperture diagram's marker the same way (marker at -position_mm: the pictures
    are turned by 180 degrees through the main lens)."""
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    photo = _open(browser, page)
    apertures = page["data"]["apertures"]
    assert len(apertures) >= 2
    select = Select(browser.find_element("id", "aperture-select"))
    assert [o.text for o in select.options] == [ap["label"] for ap in apertures]
    k = int(browser.find_element("id", "slider").get_attribute("value"))
    select.select_by_index(1)
    narrow = apertures[1]["slices"][k]
    assert photo.get_attribute("src").endswith(narrow["image"]) and "/f" in narrow["image"]
    readout = browser.find_element("id", "aperture-readout").text
    assert readout.startswith("depth of field ") and " m" in readout
    wide = apertures[0]["slices"][k]
    assert narrow["near_mm"] < wide["near_mm"]   # the narrower aperture is deeper, and the page says so
    shown_near = re.search(r"sharp from ([0-9.]+) m", browser.find_element("id", "slice-readout").text).group(1)
    assert float(shown_near) == pytest.approx(narrow["near_mm"] / 1000, rel=5e-3)   # three significant digits

    def marker_x():
        return float(browser.find_element("css selector", "#aperture circle.view.current").get_attribute("cx"))

    body = browser.find_element("tag name", "body")
    body.send_keys(Keys.ARROW_RIGHT)          # to the central view, or one step right of it
    before, view_before = marker_x(), photo.get_attribute("data-shown")
    body.send_keys(Keys.ARROW_RIGHT)
    after, view_after = marker_x(), photo.get_attribute("data-shown")
    assert view_after != view_before
    ky, kx = map(int, view_after[5:].split(","))
    kx0 = int(view_before[5:].split(",")[1])
    assert kx == kx0 + 1
    # kx + 1: near things move left in the picture (Eq. 9: view k is read at j + a(c - k)), so the camera
    # moved right, and so does its marker
    assert after > before


def test_depth_legend_labels_stay_inside_and_apart(browser, page):
    _open(browser, page)
    assert_legend_labels_apart(browser)


def test_the_focus_slider_reads_near_to_far(browser, page):
    """Issue 32: ranges read near to far: the slider's labels grow from left to right, and its left end is the
    nearest slice."""
    import re

    _open(browser, page)
    spans = browser.find_elements("css selector", "#slider-labels span")
    placed = sorted((s.location["x"], float(re.match(r"([\d.]+) m", s.text).group(1))) for s in spans)
    metres = [m for _, m in placed]
    assert len(metres) >= 2 and metres == sorted(metres), placed
    slider = browser.find_element("id", "slider")
    direction = browser.execute_script("return getComputedStyle(arguments[0]).direction;", slider)
    assert direction == "rtl"                               # index 0 (the farthest slice) on the right
