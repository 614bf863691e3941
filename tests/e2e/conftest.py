"""End-to-end fixtures: tiny models trained by the real train.py on the embedded data."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import train_tiny


@pytest.fixture(scope="session")
def text_ckpt(tmp_path_factory) -> Path:
    return train_tiny(tmp_path_factory.mktemp("text_model"))


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
