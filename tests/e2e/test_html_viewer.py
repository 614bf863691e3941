"""The HTML viewer end to end: written for a real clip, self-contained (plotly.js inline, nothing fetched), and
rendered by headless Chromium at two deep-linked frames (`#frame=K`): the screenshots show the skeleton in its
colours and differ between the frames. Skips with the reason when no Chromium/Chrome is installed (`make browser`)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from browser_helpers import pixels_near, screenshot

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.export import export_html
from motiondiff.geometry.skeleton import SMPL22

LEFT_BLUE, RIGHT_RED = (0x1F, 0x77, 0xB4), (0xD6, 0x27, 0x28)  # the viewer's limb colours


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
