"""Issue 41's web-demo cases that held in its probe and must stay (docs/reliability.md, "Issue 41's cases and their
tests"), through the real page served on a local port: a file path asked of Gradio's file routes, however it climbs
out, is refused (nothing of the machine is served), and two requests sent at once both finish, each in a request
folder of its own. (A refused request's folder and the pruning of old ones: tests/unit/demo.)"""

from __future__ import annotations

import os
import socket
import urllib.error
import urllib.request

import pytest
from hostile_cli import REPO

pytest.importorskip("gradio_client", reason="gradio is not installed: `pip install -e '.[demo]'`")


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    """(the page's URL, its output folder)."""
    os.environ.setdefault("GRADIO_ANALYTICS_ENABLED", "False")  # nothing leaves the machine
    from motiondiff.demo import DemoModels, build_demo

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    folder = tmp_path_factory.mktemp("demo")
    demo = build_demo(DemoModels(blender=False), "text", seconds=0.5, steps=2, output_dir=folder)
    demo.queue().launch(server_name="127.0.0.1", server_port=port, prevent_thread_lock=True, quiet=True)
    yield f"http://127.0.0.1:{port}/", folder
    demo.close()


def _get(url: str) -> tuple[int, bytes]:
    try:
        with urllib.request.urlopen(url, timeout=60) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as err:
        return err.code, b""


@pytest.mark.parametrize(
    "path",
    ["gradio_api/file=/etc/passwd", "gradio_api/file=../../../../../../../../etc/passwd",
     "gradio_api/file=%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "file=/etc/passwd",
     "static/../../../../../../etc/passwd", "assets/..%2f..%2f..%2f..%2f..%2f..%2fetc%2fpasswd",
     f"gradio_api/file={REPO / 'pyproject.toml'}"],
)  # fmt: skip
def test_a_path_out_of_the_page_is_not_served(page, path):
    url, _ = page
    status, body = _get(url + path)
    assert status in (400, 403, 404), f"{path}: HTTP {status}"
    assert b"root:" not in body and b"[project]" not in body


def test_two_requests_at_once_both_finish_each_in_its_own_folder(page):
    from gradio_client import Client

    url, folder = page
    client = Client(url, verbose=False, download_files=False)
    jobs = [client.submit(text=f"a person walks {k}", action=None, weights="", api_name="/on_generate")
            for k in range(2)]  # fmt: skip
    results = [job.result(timeout=600) for job in jobs]
    statuses = [result[0] for result in results]
    assert all(s.startswith("Generated 1 motion") for s in statuses), statuses
    assert [f"a person walks {k}" in s for k, s in enumerate(statuses)] == [True, True]
    runs = [p for p in folder.iterdir() if p.is_dir()]
    assert len(runs) == 2 and all(any(p.rglob("*.bvh")) for p in runs), sorted(folder.rglob("*"))
    # the files the page offers are served, by the route the test above asks for paths out of the page
    (served, *_) = [f["url"] for f in _files(results[0]) if f["url"].endswith(".bvh")]
    assert served.startswith(url + "gradio_api/file=")
    status, body = _get(served)
    assert status == 200 and body.startswith(b"HIERARCHY")


def _files(value) -> list[dict]:
    """The files (Gradio's FileData: path, url, ...) anywhere in a request's outputs."""
    if isinstance(value, dict):
        return [value] if isinstance(value.get("url"), str) else [f for v in value.values() for f in _files(v)]
    if isinstance(value, list | tuple):
        return [f for v in value for f in _files(v)]
    return []
