"""The web demo end to end: the real page (`motiondiff.demo.build_demo` over the shipped text model, few DDIM steps)
served on a free local port and driven by Selenium in headless Chromium. Generating shows the 3D viewer (its plotly
scene drawn inside the iframe), a playable MP4 and BVH/NPZ download links that serve the real files; an empty prompt
then shows the fix in the page, with no traceback. Skips with the reason when Chromium, chromedriver, Gradio or
Selenium is missing (`make browser`, `make setup`)."""

from __future__ import annotations

import io
import os
import shutil
import socket
import urllib.request
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow
SCREENSHOT = Path("/tmp/motiondiff_demo_page.png")  # kept for a look after the run


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
    for arg in ("--headless=new", "--window-size=1280,1800", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                "--disable-gpu", "--no-first-run", "--mute-audio", "--disable-dev-shm-usage"):  # fmt: skip
        options.add_argument(arg)
    if os.geteuid() == 0:
        options.add_argument("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    d = webdriver.Chrome(service=Service(chromedriver), options=options)
    d.set_page_load_timeout(60)
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
    demo = build_demo(DemoModels(), "text", seconds=1.0, steps=5, output_dir=tmp_path_factory.mktemp("demo"))
    demo.queue().launch(server_name="127.0.0.1", server_port=port, prevent_thread_lock=True, quiet=True)
    yield f"http://127.0.0.1:{port}/"
    demo.close()


def _wait(d, condition, timeout=120, what=""):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(d, timeout, poll_frequency=0.25).until(condition, message=what)


def _set_prompt(d, text: str) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    box = d.find_element(By.CSS_SELECTOR, "#prompt textarea")
    box.send_keys(Keys.CONTROL, "a")
    box.send_keys(Keys.DELETE)
    if text:
        box.send_keys(text)
    d.find_element(By.ID, "generate").click()


def _links(d, index: int) -> dict[str, str]:
    from selenium.webdriver.common.by import By

    hrefs = [a.get_attribute("href") or "" for a in d.find_elements(By.CSS_SELECTOR, f"#files-{index} a")]
    return {ext: h for h in hrefs for ext in ("bvh", "npz") if h.split("?")[0].endswith(f".{ext}")}


def test_generate_shows_viewer_video_and_downloads_then_empty_prompt_shows_the_fix(driver, demo_url):
    from selenium.webdriver.common.by import By

    d = driver
    d.get(demo_url)
    _wait(d, lambda d: d.find_elements(By.CSS_SELECTOR, "#prompt textarea"), 60, "the page did not load")
    _set_prompt(d, "a person walks forward")
    _wait(d, lambda d: len(_links(d, 0)) == 2, 180, "no BVH and NPZ download links after generating")

    # the viewer: the project's HTML viewer inside an iframe, its plotly 3D scene drawn
    frame = d.find_element(By.CSS_SELECTOR, "#viewer-0 iframe.motion-viewer")
    d.switch_to.frame(frame)
    _wait(d, lambda d: d.execute_script("return !!document.querySelector('.js-plotly-plot .gl-container canvas')"),
          60, "the viewer's 3D scene did not render")  # fmt: skip
    d.switch_to.default_content()
    # the video: served and decoded by the browser (metadata with a frame size and a duration)
    video = d.find_element(By.CSS_SELECTOR, "#video-0 video")
    size = _wait(d, lambda d: d.execute_script(
        "const v = arguments[0]; return v.readyState >= 1 && v.videoWidth > 0 ? [v.videoWidth, v.duration] : null;",
        video), 60, "the MP4 did not load in the browser")  # fmt: skip
    assert size[0] > 100 and 0.5 < size[1] < 1.5, size  # 1 s asked for
    d.save_screenshot(str(SCREENSHOT))

    # the download links serve the real files: a BVH and an NPZ of the same motion
    links = _links(d, 0)
    bvh = urllib.request.urlopen(links["bvh"], timeout=30).read().decode()
    assert bvh.startswith("HIERARCHY") and "MOTION" in bvh
    npz = np.load(io.BytesIO(urllib.request.urlopen(links["npz"], timeout=30).read()))
    assert npz["joints"].shape == (20, 22, 3) and npz["features"].shape[0] == 20 and float(npz["fps"]) == 20.0
    frames = int(bvh.split("Frames:")[1].split()[0])
    assert frames == len(npz["joints"])

    # an empty prompt: the fix in the page, no traceback, no stale result
    _set_prompt(d, "")
    status = _wait(d, lambda d: "text is empty" in d.find_element(By.ID, "status").text
                   and d.find_element(By.ID, "status").text, 60, "no empty-text message in the page")  # fmt: skip
    assert "describe the motion" in status
    page = d.find_element(By.TAG_NAME, "body").text
    assert "Traceback" not in page and 'File "' not in page
    # Gradio drops a hidden column from the page
    shown = lambda d: [e for e in d.find_elements(By.ID, "sample-0") if e.is_displayed()]  # noqa: E731
    _wait(d, lambda d: not shown(d), 10, "the old sample is still shown")
