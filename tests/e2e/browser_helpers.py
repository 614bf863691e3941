"""Headless Chromium for end-to-end tests of what a user sees in a browser (the HTML viewer, the TensorBoard
dashboard): find a browser, take a screenshot, count pixels of a colour. The `browser` fixture (conftest.py) skips
with the reason when none is installed (`make browser`)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
from PIL import Image

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_browser() -> str | None:
    if Path("/usr/bin/chromium").is_file():
        return "/usr/bin/chromium"
    return next((path for name in BROWSERS if (path := shutil.which(name))), None)


def screenshot(browser: str, url: str, out: Path, size: str = "800,600", budget_ms: int = 15000) -> np.ndarray:
    """Headless screenshot (RGB, int16). WebGL (plotly's 3D, TensorBoard's charts) runs on the software SwiftShader
    GL; ``budget_ms`` of virtual time lets the page load and draw."""
    args = [browser, "--headless", "--hide-scrollbars", "--no-first-run", "--mute-audio",
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", f"--user-data-dir={out.parent / 'profile'}",
            f"--screenshot={out}", f"--window-size={size}", f"--virtual-time-budget={budget_ms}", url]  # fmt: skip
    if os.geteuid() == 0:
        args.insert(1, "--no-sandbox")  # Chromium refuses to run as root with its sandbox
    proc = subprocess.run(args, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0 and out.is_file(), f"{browser} failed ({proc.returncode}):\n{proc.stderr[-2000:]}"
    with Image.open(out) as image:
        return np.asarray(image.convert("RGB"), dtype=np.int16)


def pixels_near(image: np.ndarray, colour: tuple[int, int, int], tol: int = 40) -> int:
    return int((np.abs(image - np.array(colour)).max(axis=-1) <= tol).sum())
