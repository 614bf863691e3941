"""The HTML viewer end to end: written for a real clip, self-contained (plotly.js inline, nothing fetched), and
rendered by headless Chromium at two deep-linked frames (`#frame=K`): the screenshots show the skeleton in its
colours and differ between the frames. Skips with the reason when no Chromium/Chrome is installed (`make browser`)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.export import export_html
from motiondiff.skeleton import SMPL22

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
LEFT_BLUE, RIGHT_RED = (0x1F, 0x77, 0xB4), (0xD6, 0x27, 0x28)  # the viewer's limb colours


def find_browser() -> str | None:
    if Path("/usr/bin/chromium").is_file():
        return "/usr/bin/chromium"
    return next((path for name in BROWSERS if (path := shutil.which(name))), None)


@pytest.fixture(scope="module")
def browser() -> str:
    path = find_browser()
    if path is None:
        pytest.skip(f"no headless browser found (tried /usr/bin/chromium and {', '.join(BROWSERS)}); `make browser`")
    return path


@pytest.fixture(scope="module")
def viewer(tmp_path_factory) -> tuple[Path, int]:
    """A viewer of the val clip 'raise-up-both-hands' (arms down at frame 0, up later), and a frame with arms up."""
    split = load_split(embedded_data_root(), "val")
    i = next(k for k in range(split.num_clips) if split.label("content", k) == "raise-up-both-hands")
    joints = split.clips()[i].joints
    wrists = [SMPL22.index("l_wrist"), SMPL22.index("r_wrist")]
    raised = int(np.argmax(joints[:, wrists, 1].min(axis=1)))
    assert joints[raised, wrists, 1].min() > joints[0, wrists, 1].max() + 0.5  # the clip really raises the hands
    path = export_html(tmp_path_factory.mktemp("viewer") / "raise.html", joints, SMPL22, 20, title="raise both hands")
    return path, raised


def screenshot(browser: str, url: str, out: Path) -> np.ndarray:
    """Headless screenshot (800x600). WebGL (plotly's 3D) runs on the software SwiftShader GL."""
    args = [browser, "--headless", "--hide-scrollbars", "--no-first-run", "--mute-audio",
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", f"--user-data-dir={out.parent / 'profile'}",
            f"--screenshot={out}", "--window-size=800,600", "--virtual-time-budget=15000", url]  # fmt: skip
    if os.geteuid() == 0:
        args.insert(1, "--no-sandbox")  # Chromium refuses to run as root with its sandbox
    proc = subprocess.run(args, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0 and out.is_file(), f"{browser} failed ({proc.returncode}):\n{proc.stderr[-2000:]}"
    with Image.open(out) as image:
        return np.asarray(image.convert("RGB"), dtype=np.int16)


def pixels_near(image: np.ndarray, colour: tuple[int, int, int], tol: int = 40) -> int:
    return int((np.abs(image - np.array(colour)).max(axis=-1) <= tol).sum())


def test_viewer_is_self_contained(viewer):
    path, _ = viewer
    html = path.read_text(encoding="utf-8")
    assert not re.search(r"<script[^>]+src\s*=\s*[\"']?(https?:)?//", html, re.I), "the viewer must not fetch scripts"
    assert not re.search(r"<link[^>]+href\s*=\s*[\"']?(https?:)?//", html, re.I)
    assert "Plotly.newPlot" in html and len(html) > 1_000_000  # plotly.js itself is inline
    assert "frame=" in html and "hashchange" in html  # the deep-link script


def test_viewer_renders_two_different_frames_in_chromium(browser, viewer, tmp_path):
    path, raised = viewer
    first = screenshot(browser, f"{path.as_uri()}#frame=0", tmp_path / "frame0.png")
    later = screenshot(browser, f"{path.as_uri()}#frame={raised}", tmp_path / f"frame{raised}.png")
    for name, image in (("frame 0", first), (f"frame {raised}", later)):
        colours = len(np.unique(image.reshape(-1, 3), axis=0))
        assert image.std() > 5 and colours > 20, f"{name}: blank screenshot (std {image.std():.1f}, {colours} colours)"
        # the 3D scene itself drew (WebGL), not just the page around it: both limb colours are on screen
        blue, red = pixels_near(image, LEFT_BLUE), pixels_near(image, RIGHT_RED)
        assert blue > 50 and red > 50, f"{name}: skeleton not drawn ({blue} blue, {red} red pixels)"
    changed = int((np.abs(first - later).max(axis=-1) > 30).sum())
    print(f"\nviewer frames 0 and {raised}: {changed} pixels differ")
    assert changed > 500, "the deep link #frame=K must show another pose than frame 0"
