"""Shared fixtures. Tests that read ../shared (CI has it) skip with a reason where it is absent (a user's clone)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("MOTIONDIFF_SHARED", REPO.parent / "shared"))


def _shared_path(*parts: str) -> Path:
    path = SHARED.joinpath(*parts)
    if not path.exists():
        pytest.skip(f"{path} not found: this test needs the project's shared data (set MOTIONDIFF_SHARED)")
    return path


@pytest.fixture(scope="session")
def shared():
    """Callable fixture: shared('reference', 'humanml3d') -> Path, or skip when missing."""
    return _shared_path


@pytest.fixture(autouse=True, scope="session")
def _keep_caches_out_of_home(tmp_path_factory):
    """Tool caches (wandb, matplotlib, HF) go to a temp dir, never into the user's home."""
    cache = tmp_path_factory.mktemp("caches")
    for var, sub in [("WANDB_DIR", "wandb"), ("WANDB_CACHE_DIR", "wandb-cache"), ("WANDB_CONFIG_DIR", "wandb-config"),
                     ("MPLCONFIGDIR", "mpl"), ("HF_HOME", "hf"), ("XDG_CACHE_HOME", "xdg")]:  # fmt: skip
        os.environ[var] = str(cache / sub)
    os.environ.setdefault("WANDB_MODE", "offline")
    os.environ.setdefault("HF_HUB_OFFLINE", "1")
    os.environ.setdefault("TRANSFORMERS_OFFLINE", "1")
    yield
