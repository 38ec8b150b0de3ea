"""The picture viewer in a real browser: a click on a region shows the focus stack image sharpest there.

Uses the headless Chromium fixture of ``test_browser_viewer`` (same skip/fail rules: required in CI).
"""

import numpy as np

import lytropics
from conftest import run_cli
from test_browser_viewer import browser  # noqa: F401  (the fixture)

LAMBDAS = (-8.92, -2.6, 5.0)     # F01 metadata: all in front of infinity (infinityLambda 7)


def test_click_shows_the_sharpest_stack_image_and_its_distance(browser, tmp_path):  # noqa: F811
    from selenium.webdriver.common.action_chains import ActionChains

    picture = lytropics.write(tmp_path / "IMG-stk.lfp", lytropics.first_gen_stack(LAMBDAS))
    assert run_cli("viewer", picture, "-o", tmp_path / "v").returncode == 0
    browser.get((tmp_path / "v" / "index.html").as_uri())
    photo = browser.find_element("id", "photo")
    width = photo.size["width"]
    for k in (2, 0, 1):     # image k is sharp in vertical band k of 3
        x = (k + 0.5) / len(LAMBDAS) * width - width / 2
        ActionChains(browser).move_to_element_with_offset(photo, int(round(x)), 0).click().perform()
        assert photo.get_attribute("data-shown") == str(k)
        readout = browser.find_element("id", "readout").text
        assert f"lambda {LAMBDAS[k]:g}" in readout and "from the sensor" in readout and " m " in readout
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, errors
    assert np.isfinite(width) and width >= 512
