"""The web demo end to end: the real page (`motiondiff.demo.build_demo` over the shipped text model, 5 DDIM steps, 1 s
motions) served on a free local port and driven by Selenium in headless Chromium through every mode, as a user:

- Generate: an example prompt clicked in, guidance, seed and samples set, three samples side by side, each with the
  3D viewer drawn, a playing MP4 and BVH/NPZ links that serve the real files, and a zip of everything;
- Edit body parts of sample 2 on the page: the legs (kept) are those of sample 2, in the files the page serves;
- In-between from an uploaded BVH (the one downloaded above): the kept start and end frames are reported;
- Timeline: an example timeline clicked in, then two timed prompts, one far from the training captions: the timeline
  bar shows both and the prompt-coverage warning names the far one;
- an empty prompt shows the fix in the page, with no traceback and no stale result.

Every step's screenshot goes to a temporary folder; with MOTIONDIFF_SAVE_SCREENSHOTS=1 also to docs/images/demo/
(the ones docs/demo.md shows; that run lets Blender write FBX/GLB where it is installed, and checks their links).
Skips with the reason when Chromium, chromedriver, Gradio or Selenium is missing (`make browser`, `make setup`).
"""

from __future__ import annotations

import io
import os
import re
import shutil
import socket
import urllib.request
import zipfile
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow
DOCS_IMAGES = Path(__file__).resolve().parents[2] / "docs" / "images" / "demo"
SAVE = os.environ.get("MOTIONDIFF_SAVE_SCREENSHOTS") == "1"
WIDTH, HEIGHT = 1280, 900  # the screenshots' size
MAX_PNG_BYTES = 300_000
VIDEO_SIZE = 360  # pixels: small videos keep the test quick
FAR_PROMPT = "a person plays the violin underwater"


def _tool(paths: tuple[str, ...], names: tuple[str, ...]) -> str | None:
    return next((p for p in paths if Path(p).is_file()), None) or next(
        (found for n in names if (found := shutil.which(n))), None
    )


@pytest.fixture(scope="module")
def driver():
    pytest.importorskip("selenium", reason="selenium is not installed: `make setup` (the dev extra)")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    browser = _tool(("/usr/bin/chromium",), ("chromium", "chromium-browser", "google-chrome"))
    chromedriver = _tool(("/usr/bin/chromedriver",), ("chromedriver",))
    if browser is None or chromedriver is None:
        pytest.skip(f"needs Chromium and chromedriver (found browser={browser}, chromedriver={chromedriver}); "
                    "`make browser` installs Debian's chromium and chromium-driver")  # fmt: skip
    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for arg in ("--headless=new", f"--window-size={WIDTH},{HEIGHT}", "--use-angle=swiftshader", "--hide-scrollbars",
                "--enable-unsafe-swiftshader", "--disable-gpu", "--no-first-run", "--mute-audio",
                "--disable-dev-shm-usage"):  # fmt: skip
        options.add_argument(arg)
    if os.geteuid() == 0:
        options.add_argument("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    d = webdriver.Chrome(service=Service(chromedriver), options=options)
    d.set_page_load_timeout(60)
    # the viewport itself WIDTH x HEIGHT (the window size includes the browser's frame)
    d.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                      {"width": WIDTH, "height": HEIGHT, "deviceScaleFactor": 1, "mobile": False})  # fmt: skip
    yield d
    d.quit()


@pytest.fixture(scope="module")
def demo_url(tmp_path_factory):
    os.environ.setdefault("GRADIO_ANALYTICS_ENABLED", "False")  # nothing leaves the machine
    pytest.importorskip("gradio", reason="gradio is not installed: `pip install -e '.[demo]'`")
    from motiondiff.demo import DemoModels, build_demo

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    models = DemoModels(blender=None if SAVE else False)  # Blender (seconds per file) only for the docs' run
    demo = build_demo(models, "text", seconds=1.0, steps=5, video_size=VIDEO_SIZE,
                      output_dir=tmp_path_factory.mktemp("demo"))  # fmt: skip
    demo.queue().launch(server_name="127.0.0.1", server_port=port, prevent_thread_lock=True, quiet=True)
    yield f"http://127.0.0.1:{port}/", models
    demo.close()


@pytest.fixture(scope="module")
def shots(tmp_path_factory):
    return tmp_path_factory.mktemp("screenshots")


# ---- page helpers -------------------------------------------------------------------------------------------------
def _wait(d, condition, timeout=180, what=""):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(d, timeout, poll_frequency=0.25).until(condition, message=what)


def _css(d, selector):
    from selenium.webdriver.common.by import By

    return d.find_elements(By.CSS_SELECTOR, selector)


def _type(d, selector: str, text: str, submit: bool = False) -> None:
    from selenium.webdriver.common.keys import Keys

    box = _css(d, selector)[0]
    box.send_keys(Keys.CONTROL, "a")
    box.send_keys(Keys.DELETE)
    if text:
        box.send_keys(text)
    box.send_keys(Keys.ENTER if submit else Keys.TAB)  # a slider's number box takes its value on leaving it


def _click(d, selector: str) -> None:
    element = _css(d, selector)[0]
    d.execute_script("arguments[0].scrollIntoView({block: 'center'});", element)
    element.click()


def _tab(d, name: str) -> None:
    _click(d, f"#tab-{name}-button")
    _wait(d, lambda d: _css(d, f"#tab-{name}-button")[0].get_attribute("aria-selected") == "true", 10, name)


def _status(d) -> str:
    return _css(d, "#status")[0].text


def _shown(d) -> list[int]:
    """The result columns on the page (Gradio drops hidden ones)."""
    return [i for i in range(4) if any(e.is_displayed() for e in _css(d, f"#sample-{i}"))]


def _links(d, index: int) -> dict[str, str]:
    hrefs = [a.get_attribute("href") or "" for a in _css(d, f"#files-{index} a")]
    return {h.split("?")[0].rsplit(".", 1)[-1]: h for h in hrefs if "." in h}


def _run(d, button: str, done, what: str, timeout: float = 240) -> str:
    """Press ``button`` and wait until the status line says ``done`` (text in it) and sample 1 has its links."""
    before = _status(d)
    _click(d, button)
    _wait(d, lambda d: _status(d) != before and done in _status(d) and {"bvh", "npz"} <= set(_links(d, 0)),
          timeout, f"{what}: no result (status: {_status(d)!r})")  # fmt: skip
    page = _css(d, "body")[0].text
    assert "Traceback" not in page and "Please fix" not in page, page[-2000:]
    return _status(d)


def _get(url: str) -> bytes:
    return urllib.request.urlopen(url, timeout=30).read()


def _npz(url: str):
    return np.load(io.BytesIO(_get(url)))


def _viewer_frames(d, index: int) -> int:
    """The frame count the 3D viewer of sample ``index`` reports once it has drawn (its data-frames hook)."""
    frame = _css(d, f"#viewer-{index} iframe.motion-viewer")[0]
    d.switch_to.frame(frame)
    try:
        return int(_wait(d, lambda d: d.execute_script(
            "const v = document.querySelector('.motion-viewer'); return v && v.dataset.frames;"), 60,
            f"the 3D viewer of sample {index + 1} did not draw"))  # fmt: skip
    finally:
        d.switch_to.default_content()


def _video(d, index: int) -> list:
    video = _css(d, f"#video-{index} video")[0]
    return _wait(d, lambda d: d.execute_script(
        "const v = arguments[0]; return v.readyState >= 1 && v.videoWidth > 0 ? [v.videoWidth, v.duration] : null;",
        video), 60, f"the MP4 of sample {index + 1} did not load")  # fmt: skip


def _shot(d, folder: Path, name: str, anchor: str) -> None:
    """Screenshot with ``anchor`` at the top of the view, into ``folder`` and, with SAVE, into docs (as a palette
    PNG when the full-colour one is over MAX_PNG_BYTES)."""
    from PIL import Image

    d.execute_script("window.scrollTo(0, arguments[0].getBoundingClientRect().top + window.scrollY - 8);",
                     _css(d, anchor)[0])  # fmt: skip
    d.execute_script("document.activeElement && document.activeElement.blur();")
    path = folder / f"{name}.png"
    d.save_screenshot(str(path))
    with Image.open(path) as image:
        assert image.size == (WIDTH, HEIGHT), image.size
        if path.stat().st_size > MAX_PNG_BYTES:
            image.convert("RGB").quantize(256, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    assert path.stat().st_size <= MAX_PNG_BYTES, (path, path.stat().st_size)
    if SAVE:
        DOCS_IMAGES.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, DOCS_IMAGES / path.name)


# ---- the test -----------------------------------------------------------------------------------------------------
def test_every_mode_in_the_browser(driver, demo_url, shots, tmp_path):
    d, (url, models) = driver, demo_url
    blender, info = models.glb, models.info("text")
    d.get(url)
    _wait(d, lambda d: _css(d, "#examples button.gallery-item"), 60, "the page did not load with example prompts")
    assert "checks each prompt against its training captions" in _css(d, "#coverage-note")[0].text

    # Generate: an example prompt, guidance 2.5, seed 7, three samples side by side
    example = _css(d, "#examples button.gallery-item")[2]
    prompt = example.text.strip()
    assert (
        prompt == info.examples[2]
        and [e.text.strip() for e in _css(d, "#examples button.gallery-item")] == info.examples
    )
    example.click()
    _wait(d, lambda d: _css(d, "#prompt textarea, #prompt input")[0].get_attribute("value") == prompt, 10,
          "clicking an example did not fill the prompt")  # fmt: skip
    _type(d, "#guidance input[type=number]", "2.5")
    _type(d, "#seed input", "7")
    _type(d, "#samples input[type=number]", "3")
    status = _run(d, "#generate", "Generated 3 motion(s)", "generate")
    assert f"of {prompt!r}" in status and "guidance 2.5" in status and "seed 7" in status, status
    _wait(d, lambda d: _shown(d) == [0, 1, 2], 30, "three result columns")
    boxes = [_css(d, f"#sample-{i}")[0].rect for i in range(3)]
    assert len({round(b["y"]) for b in boxes}) == 1 and boxes[0]["x"] < boxes[1]["x"] < boxes[2]["x"], boxes
    for i in range(3):
        assert _viewer_frames(d, i) == 20  # 1 s at 20 fps
        width, seconds = _video(d, i)
        assert width == VIDEO_SIZE and 0.5 < seconds < 1.5
    links = [_links(d, i) for i in range(3)]
    assert all(({"bvh", "npz", "fbx", "glb"} if blender else {"bvh", "npz"}) == set(k) for k in links), links
    bvh = _get(links[1]["bvh"]).decode()
    assert bvh.startswith("HIERARCHY") and int(bvh.split("Frames:")[1].split()[0]) == 20
    sample_2 = _npz(links[1]["npz"])
    assert sample_2["joints"].shape == (20, 22, 3) and float(sample_2["fps"]) == 20.0
    upload = tmp_path / "my_motion.bvh"
    upload.write_text(bvh)
    names = zipfile.ZipFile(io.BytesIO(_get(_css(d, "#zip a")[0].get_attribute("href")))).namelist()
    for ext in ("bvh", "npz", "mp4", "html"):
        assert sum(n.endswith(f".{ext}") for n in names) == 3, (ext, names)
    _shot(d, shots, "01-page", "body")
    _shot(d, shots, "02-generate", "#tab-generate-button")

    # Edit body parts of sample 2 on the page: the upper body regenerated, the legs kept
    _type(d, "#samples input[type=number]", "1")
    _tab(d, "edit")
    _type(d, "#edit-sample input[type=number]", "2")
    _type(d, "#prompt textarea, #prompt input", "a person raises both hands")
    status = _run(d, "#edit", "Regenerated upper_body", "edit")
    assert "of sample 2 on the page" in status and "the rest of the body is kept" in status, status
    assert _shown(d) == [0]
    edited = _npz(_links(d, 0)["npz"])["joints"]
    from motiondiff.geometry.skeleton import SMPL22

    legs = list(SMPL22.parts["lower_body"])
    arms = [j for j in SMPL22.parts["upper_body"] if j not in legs]
    assert np.abs(edited[:, legs] - sample_2["joints"][:, legs]).max() < 1e-3  # sample 2's legs, as served
    assert np.abs(edited[:, arms] - sample_2["joints"][:, arms]).max() > 1e-2
    _shot(d, shots, "03-edit", "#tab-edit-button")

    # In-between from the uploaded BVH: its first and last quarter kept
    _tab(d, "inbetween")
    _css(d, "#inbetween-upload input[type=file]")[0].send_keys(str(upload))
    uploaded = lambda d: [e.get_attribute("aria-label") for e in _css(d, "#inbetween-upload td.filename")]  # noqa: E731
    _wait(d, uploaded, 30, "the BVH did not upload")
    assert uploaded(d) == ["my_motion.bvh"]
    _type(d, "#prompt textarea, #prompt input", "a person walks")
    status = _run(d, "#inbetween", "Kept the first", "in-between")
    assert "of the upload my_motion.bvh" in status and "from 'a person walks'" in status, status
    first, last, frames = map(
        int, re.search(r"Kept the first (\d+) and the last (\d+) of (\d+) frames", status).groups()
    )
    assert first == last == round(0.25 * frames) and first > 0, status  # the default: a quarter each
    assert _viewer_frames(d, 0) == frames
    _shot(d, shots, "04-inbetween", "#tab-inbetween-button")

    # Timeline: an example timeline fills the box; two timed prompts, one far from the training captions
    _tab(d, "timeline")
    assert _css(d, "#timeline textarea")[0].get_attribute("value") == info.timelines[0]
    _css(d, "#timeline-examples button.gallery-item")[1].click()
    _wait(d, lambda d: _css(d, "#timeline textarea")[0].get_attribute("value") == info.timelines[1], 10,
          "clicking an example timeline did not fill the box")  # fmt: skip
    _type(d, "#timeline textarea", "")
    _css(d, "#timeline textarea")[0].send_keys(f"a person walks : 1\n{FAR_PROMPT} : 1")
    status = _run(d, "#make-timeline", "through 2 timed prompts", "timeline")
    assert "of 2.0 s" in status, status
    segments = [e.text for e in _css(d, "#timeline-bar .segment")]
    assert segments == ["a person walks 0.0-1.0 s", f"{FAR_PROMPT} 1.0-2.0 s"], segments
    warning = _css(d, "#coverage")[0]
    assert warning.is_displayed() and FAR_PROMPT in warning.text and "far from everything" in warning.text
    assert "a person walks'" not in warning.text  # the near prompt is not flagged
    assert _viewer_frames(d, 0) == 40
    _shot(d, shots, "05-timeline", "#tab-timeline-button")

    # an empty prompt: the fix in the page, no traceback, no stale result
    _tab(d, "generate")
    _type(d, "#prompt textarea, #prompt input", "")
    _click(d, "#generate")
    _wait(d, lambda d: "text is empty" in _status(d), 60, "no empty-text message in the page")
    assert "describe the motion" in _status(d)
    page = _css(d, "body")[0].text
    assert "Traceback" not in page and 'File "' not in page
    _wait(d, lambda d: not _shown(d) and not _css(d, "#timeline-bar .segment"), 10, "the old result is still shown")
    assert not any(e.is_displayed() for e in _css(d, "#coverage, #zip"))
