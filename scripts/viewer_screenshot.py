#!/usr/bin/env python
"""Screenshot of the viewer on the bundled sample for the README → docs/viewer.png (< 150 kB).

Builds the sample's viewer with ``lfproc viewer`` (the demo's slices, 369 to 1236 mm), opens it in
headless Chromium (Debian's ``chromium`` and ``chromedriver``, driven by Selenium), clicks on the
checkerboard card at 650 mm and saves the window, reduced to a 256-colour PNG.

Usage: ``python scripts/viewer_screenshot.py [--out docs/viewer.png]``.
"""

from __future__ import annotations

import argparse
import io
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SAMPLE = ROOT / "samples" / "sample"
CLICK_AT = (0.22, 0.55)  # fraction of the picture's width and height: on the checkerboard card


def build(outdir: Path) -> Path:
    subprocess.run([sys.executable, "-m", "lfproc", "viewer", str(SAMPLE / "capture.png"), "--camera",
                    str(SAMPLE / "camera.toml"), "--white", str(SAMPLE / "white.png"), "--depth-range", "369:1236",
                    "-o", str(outdir)], check=True, cwd=ROOT)
    return outdir / "index.html"


def screenshot(page: Path, profile: str) -> bytes:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import WebDriverWait

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or shutil.which("chromium-browser")
    for arg in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                "--disable-background-networking", "--disable-component-update", "--disable-sync",
                "--window-size=1180,800", "--hide-scrollbars", f"--user-data-dir={profile}"):
        options.add_argument(arg)
    driver = webdriver.Chrome(options=options, service=Service(shutil.which("chromedriver")))
    try:
        driver.get(page.as_uri())
        WebDriverWait(driver, 10).until(lambda d: d.execute_script("return document.body.dataset.ready === 'true'"))
        photo = driver.find_element("id", "photo")
        size = photo.size
        ActionChains(driver).move_to_element_with_offset(
            photo, int((CLICK_AT[0] - 0.5) * size["width"]), int((CLICK_AT[1] - 0.5) * size["height"])).click().perform()
        return driver.get_screenshot_as_png()
    finally:
        driver.quit()


def main() -> None:
    from PIL import Image

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "viewer.png"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        png = screenshot(build(Path(tmp) / "viewer"), str(Path(tmp) / "profile"))
    image = Image.open(io.BytesIO(png)).convert("RGB")
    image = image.resize((image.width * 3 // 4, image.height * 3 // 4), Image.LANCZOS)
    image.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(args.out, optimize=True)
    print(f"{args.out}: {image.width} x {image.height}, {Path(args.out).stat().st_size / 1000:.0f} kB")


if __name__ == "__main__":
    main()
