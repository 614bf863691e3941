"""The HTML viewer end to end: written for a real clip, self-contained (its script inline, nothing fetched) and
small (a 10 s, 200-frame motion is at most 300 KB), with positions that decode back to the joints and body pieces
that are the videos' mannequin; rendered by headless Chromium at two deep-linked frames (`#frame=K`): the screenshots
show the body in its left/right tints and differ between the frames, and a file written without the body shows the
bones instead. A file copied alone into an empty folder (as a user e-mails one) opens in Selenium-driven Chromium with
no script error: it reports its frame count, follows the deep link, plays, pauses, turns the camera on a drag, and
its Body/Bones button switches between the body and the bones. Skips with the reason when no Chromium/Chrome
(`make browser`), chromedriver or Selenium is installed."""

from __future__ import annotations

import base64
import io
import json
import os
import re
import shutil
import time
from pathlib import Path

import numpy as np
import pytest
from browser_helpers import pixels_near, screenshot
from PIL import Image

from motiondiff.data.datamodules import embedded_data_root
from motiondiff.data.formats.prepared import load_split
from motiondiff.export import export_html
from motiondiff.export.body_render import mannequin_mesh
from motiondiff.geometry.mannequin import build_mannequin
from motiondiff.geometry.skeleton import SMPL22

LEFT_BLUE, RIGHT_RED = (0x1F, 0x77, 0xB4), (0xD6, 0x27, 0x28)  # the viewer's limb colours
SIZE_BUDGET = 300_000  # bytes for one motion's file (issue 42)
TITLES = [(0, "a person walks"), (120, "then waves")]  # a long motion's per-segment titles


def payload(path: Path) -> dict:
    """The JSON the viewer's script reads."""
    html = path.read_text(encoding="utf-8")
    return json.loads(re.search(r'<script type="application/json" class="motion-data">(.*?)</script>', html).group(1))


def rgb(hex_colour: str) -> tuple[int, int, int]:
    return tuple(int(hex_colour[i : i + 2], 16) for i in (1, 3, 5))


def body_and_bone_pixels(image: np.ndarray, path: Path) -> tuple[int, int]:
    """(pixels in the body's left or right tint, pixels in the bones' left or right colour) of the canvas, or of a
    screenshot of the page less its bottom bar (the slider is blue), of the viewer file `path`."""
    tints = payload(path)["style"]["body"]
    body = pixels_near(image, rgb(tints["left"])) + pixels_near(image, rgb(tints["right"]))
    return body, pixels_near(image, LEFT_BLUE) + pixels_near(image, RIGHT_RED)


@pytest.fixture(scope="module")
def val_split():
    return load_split(embedded_data_root(), "val")


@pytest.fixture(scope="module")
def viewer(tmp_path_factory, val_split) -> tuple[Path, int]:
    """A viewer of the val clip 'raise-up-both-hands' (arms down at frame 0, up later), and a frame with arms up."""
    i = next(k for k in range(val_split.num_clips) if val_split.label("content", k) == "raise-up-both-hands")
    joints = val_split.clips()[i].joints
    wrists = [SMPL22.index("l_wrist"), SMPL22.index("r_wrist")]
    raised = int(np.argmax(joints[:, wrists, 1].min(axis=1)))
    assert joints[raised, wrists, 1].min() > joints[0, wrists, 1].max() + 0.5  # the clip really raises the hands
    path = export_html(tmp_path_factory.mktemp("viewer") / "raise.html", joints, SMPL22, 20, title="raise both hands")
    return path, raised


@pytest.fixture(scope="module")
def bones_viewer(tmp_path_factory, val_split, viewer) -> Path:
    """The same clip written with body=False: bones only."""
    i = next(k for k in range(val_split.num_clips) if val_split.label("content", k) == "raise-up-both-hands")
    return export_html(tmp_path_factory.mktemp("bones") / "raise.html", val_split.clips()[i].joints, SMPL22, 20,
                       title="raise both hands", body=False)  # fmt: skip


@pytest.fixture(scope="module")
def ten_seconds(tmp_path_factory, val_split) -> tuple[Path, np.ndarray]:
    """A 10 s motion at 20 fps (200 frames of real val clips played one after another) with two titled segments."""
    joints = np.concatenate([clip.joints for clip in val_split.clips()])[:200]
    assert joints.shape == (200, 22, 3)
    return export_html(tmp_path_factory.mktemp("long") / "motion.html", joints, SMPL22, 20, title=TITLES), joints


def test_viewer_is_self_contained(viewer):
    path, _ = viewer
    html = path.read_text(encoding="utf-8")
    assert not re.search(r"<script[^>]+src\s*=", html, re.I), "the viewer's script must be inline, not fetched"
    assert not re.search(r"<link[^>]+href\s*=", html, re.I)
    assert not re.search(r"https?://", html), "the viewer must not reach the network"
    assert 'class="motion-data"' in html and "hashchange" in html  # the motion and the deep-link script


def test_ten_second_motion_is_small_and_decodes_to_its_joints(ten_seconds):
    path, joints = ten_seconds
    size = path.stat().st_size
    print(f"\n200-frame, 22-joint viewer: {size} bytes")
    assert size <= SIZE_BUDGET, f"{size} bytes for a 10 s motion; the budget is {SIZE_BUDGET}"
    data = payload(path)
    steps = np.frombuffer(base64.b64decode(data["positions"]), dtype="<u2").reshape(data["frames"], data["joints"], 3)
    decoded = np.asarray(data["origin"]) + data["step"] * steps
    assert np.abs(decoded - joints).max() <= 0.0006  # what the browser draws is the motion, to 1 mm steps
    assert data["titles"] == [list(t) for t in TITLES]


def test_body_pieces_are_the_videos_mannequin(ten_seconds):
    """Every vertex of render=body's mannequin lies on the file's capsule of its piece: at the piece's radius at
    that end from the end point the file's rule places on the frame's joints (`html_viewer._body_pieces`), so the
    viewer's body and the video's are the same shapes."""
    path, joints = ten_seconds
    pieces = payload(path)["body"]
    frames = joints[::25].astype(np.float64)
    vertices, _ = mannequin_mesh(frames, SMPL22)
    labels = build_mannequin(SMPL22)  # which piece and end each vertex belongs to (the skeleton's, not the sizes')
    assert len(pieces) == len(labels.joint) and {piece[8] for piece in pieces} == {"left", "right", "torso"}
    ends, radii = np.zeros((len(frames), len(pieces), 2, 3)), np.zeros((len(pieces), 2))
    for p, piece in enumerate(pieces):
        for e in (0, 1):
            joint, toward, reach, radii[p, e] = piece[4 * e : 4 * e + 4]
            bone = frames[:, joint] - frames[:, toward] if toward >= 0 else np.zeros_like(frames[:, joint])
            unit = bone / np.maximum(np.linalg.norm(bone, axis=-1, keepdims=True), 1e-9)
            ends[:, p, e] = frames[:, joint] + reach * unit
    end = labels.t.astype(int)
    distance = np.linalg.norm(vertices - ends[:, labels.piece, end], axis=-1)
    error = np.abs(distance - radii[labels.piece, end]).max()
    assert error < 1e-3, f"a mannequin vertex is {error:.4f} m off the viewer's capsule of its piece"


def test_viewer_renders_two_different_frames_in_chromium(browser, viewer, tmp_path):
    path, raised = viewer
    first = screenshot(browser, f"{path.as_uri()}#frame=0", tmp_path / "frame0.png", budget_ms=2000)
    later = screenshot(browser, f"{path.as_uri()}#frame={raised}", tmp_path / f"frame{raised}.png", budget_ms=2000)
    for name, image in (("frame 0", first), (f"frame {raised}", later)):
        colours = len(np.unique(image.reshape(-1, 3), axis=0))
        assert image.std() > 5 and colours > 20, f"{name}: blank screenshot (std {image.std():.1f}, {colours} colours)"
        # the scene itself drew, not just the page around it: both sides' body tints are on screen
        tints = payload(path)["style"]["body"]
        left, right = (pixels_near(image, rgb(tints[side])) for side in ("left", "right"))
        assert left > 300 and right > 300, f"{name}: body not drawn ({left} left-, {right} right-tinted pixels)"
    changed = int((np.abs(first - later).max(axis=-1) > 30).sum())
    print(f"\nviewer frames 0 and {raised}: {changed} pixels differ")
    assert changed > 500, "the deep link #frame=K must show another pose than frame 0"


def test_body_is_drawn_unless_turned_off(browser, viewer, bones_viewer, tmp_path):
    """The default file draws the mannequin (many body-tinted pixels, few in the bones' colours); body=False draws
    the bones instead, and writes no body pieces."""
    path, raised = viewer
    body = screenshot(browser, f"{path.as_uri()}#frame={raised}", tmp_path / "body.png", budget_ms=2000)
    bones = screenshot(browser, f"{bones_viewer.as_uri()}#frame={raised}", tmp_path / "bones.png", budget_ms=2000)
    (body_tinted, body_sticks), (bones_tinted, bones_sticks) = (body_and_bone_pixels(image[:-50], path)
                                                                for image in (body, bones))  # fmt: skip
    print(f"\nbody on: {body_tinted} tinted, {body_sticks} stick-coloured pixels; "
          f"off: {bones_tinted} tinted, {bones_sticks} stick-coloured")  # fmt: skip
    assert body_tinted > 1000 and body_tinted > 3 * bones_tinted, "the body is not drawn, or drawn without it"
    assert bones_sticks > 500 and bones_sticks > 10 * body_sticks, "body=False must draw the bones"
    assert payload(bones_viewer)["body"] is None and len(payload(path)["body"]) > 15


@pytest.fixture(scope="module")
def driver(browser):
    """Selenium's Chrome driver on the `browser` fixture's Chromium, keeping the page's console log."""
    pytest.importorskip("selenium", reason="selenium is not installed: `make setup` (the dev extra)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    chromedriver = next((p for p in ("/usr/bin/chromedriver", shutil.which("chromedriver")) if p and Path(p).is_file()),
                        None)  # fmt: skip
    if chromedriver is None:
        pytest.skip("needs chromedriver: `make browser` installs Debian's chromium and chromium-driver")
    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for arg in ("--headless=new", "--window-size=800,600", "--no-first-run", "--mute-audio", "--disable-dev-shm-usage"):
        options.add_argument(arg)
    if os.geteuid() == 0:
        options.add_argument("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    d = webdriver.Chrome(service=Service(chromedriver), options=options)
    d.set_page_load_timeout(60)
    yield d
    d.quit()


def page_image(d) -> np.ndarray:
    with Image.open(io.BytesIO(d.get_screenshot_as_png())) as png:
        return np.asarray(png.convert("RGB"), dtype=np.int16)


def canvas_image(d, canvas) -> np.ndarray:
    url = d.execute_script("return arguments[0].toDataURL()", canvas)
    with Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))) as png:
        return np.asarray(png.convert("RGB"), dtype=np.int16)


def test_file_copied_alone_opens_plays_and_turns(driver, ten_seconds, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    alone = tmp_path / "emailed" / "motion.html"
    alone.parent.mkdir()
    shutil.copy(ten_seconds[0], alone)
    assert [p.name for p in alone.parent.iterdir()] == ["motion.html"]
    d = driver
    d.get(f"{alone.as_uri()}#frame=150")
    viewer = d.find_element(By.CSS_SELECTOR, ".motion-viewer")
    shown = lambda: int(viewer.get_attribute("data-frame"))  # noqa: E731
    assert viewer.get_attribute("data-frames") == "200" and shown() == 150
    assert d.find_element(By.CSS_SELECTOR, ".mv-title").text == "then waves"  # the segment playing at frame 150
    errors = [e for e in d.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"script errors: {errors}"
    image = page_image(d)
    tinted, _ = body_and_bone_pixels(image, alone)
    assert image.std() > 5 and tinted > 1000, f"blank or no body ({tinted} body-tinted pixels)"
    canvas = d.find_element(By.CSS_SELECTOR, ".mv-canvas")
    pixels = lambda: d.execute_script("return arguments[0].toDataURL()", canvas)  # noqa: E731
    before = pixels()

    d.execute_script("window.location.hash = 'frame=10'")  # a new deep link on an open page
    WebDriverWait(d, 10).until(lambda _: shown() == 10, "the page did not follow the hash change")
    redrawn = pixels() != before
    assert d.find_element(By.CSS_SELECTOR, ".mv-title").text == "a person walks" and redrawn

    play = d.find_element(By.CSS_SELECTOR, ".mv-play")
    play.click()
    WebDriverWait(d, 10).until(lambda _: shown() > 12, "Play did not advance the frames")
    play.click()
    assert play.text == "Play"
    paused = shown()
    time.sleep(0.3)  # 6 frames at 20 fps: a page still playing would have moved on
    assert shown() == paused, "Pause did not stop the playback"

    still = pixels()
    ActionChains(d).move_to_element(canvas).click_and_hold().move_by_offset(120, 0).release().perform()
    turned = pixels() != still
    assert shown() == paused and turned, "dragging must turn the camera, not change the frame"


def test_body_bones_button_switches_the_view(driver, viewer):
    """The viewer opens on the body; its button switches to the bones (the body-tinted pixels go, the bones' colours
    come) and back, on the same frame."""
    from selenium.webdriver.common.by import By

    path, raised = viewer
    d = driver
    d.get(f"{path.as_uri()}#frame={raised}")
    viewer = d.find_element(By.CSS_SELECTOR, ".motion-viewer")
    button = d.find_element(By.CSS_SELECTOR, ".mv-view")
    canvas = d.find_element(By.CSS_SELECTOR, ".mv-canvas")
    seen = []
    for view, label in (("body", "Show bones"), ("bones", "Show body"), ("body", "Show bones")):
        if seen:
            button.click()
        assert (viewer.get_attribute("data-view"), button.text) == (view, label)
        assert viewer.get_attribute("data-frame") == str(raised), "switching the view must keep the frame"
        seen.append(body_and_bone_pixels(canvas_image(d, canvas), path))
    (body_tinted, body_sticks), (bones_tinted, bones_sticks), again = seen
    print(f"\nbody: {body_tinted} tinted, {body_sticks} stick pixels; bones: {bones_tinted}, {bones_sticks}")
    assert body_tinted > 1000 and body_tinted > 3 * bones_tinted, "the button did not hide the body"
    assert bones_sticks > 500 and bones_sticks > 10 * body_sticks, "the button did not show the bones"
    assert again == seen[0], "switching back must draw the body as before"
    errors = [e for e in d.get_log("browser") if e["level"] == "SEVERE"]
    assert not errors, f"script errors: {errors}"
