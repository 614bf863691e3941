"""End-to-end fixtures: tiny models trained by the real train.py on the embedded data."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from cli_helpers import SHARED_TEXT_CACHE, train_tiny


@pytest.fixture(autouse=True, scope="session")
def _shared_text_cache(tmp_path_factory):
    """One caption-feature cache for the session's runs (both xdist workers': the folder above their own temp)."""
    base = tmp_path_factory.getbasetemp()
    folder = (base.parent if base.name.startswith("popen-gw") else base) / "shared-text-cache"
    folder.mkdir(parents=True, exist_ok=True)
    os.environ[SHARED_TEXT_CACHE] = str(folder)
    yield


@pytest.fixture(scope="session")
def text_ckpt(tmp_path_factory) -> Path:
    return train_tiny(tmp_path_factory.mktemp("text_model"), process=True)  # train.py as a process, once per worker


@pytest.fixture(scope="session")
def action_ckpt(tmp_path_factory) -> Path:
    # also runs the `make train` preset (cosine lr, EMA weights) for a few steps
    return train_tiny(tmp_path_factory.mktemp("action_model"), "condition=action", "experiment=cpu_quickstart")


@pytest.fixture(scope="module")
def browser() -> str:
    """A headless Chromium/Chrome (browser_helpers), or skip with the reason."""
    from browser_helpers import BROWSERS, find_browser

    path = find_browser()
    if path is None:
        pytest.skip(f"no headless browser found (tried /usr/bin/chromium and {', '.join(BROWSERS)}); `make browser`")
    return path
